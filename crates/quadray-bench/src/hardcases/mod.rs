//! Generators for the hard-case catalogue (quadric-numerics.md §4), every family for every quadric
//! kind where it applies. Generation only needs plausible rays: the oracle decides what each one
//! really hits, and how close it comes to a decision boundary.

mod families;

pub use families::{
    apex, asymptote, axis_parallel, clip_face, far, huge, inside, negative_a, open_cup, scene,
    tangent, thin_ellipsoid, waist,
};

use glam::DVec3;
use quadray::{ClipBox, Coefficients, Quadric, QuadricKind, QuadricSurface, Ray, Transform};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// One ray against one quadric of a family.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Case {
    /// Index into [`Family::quadrics`].
    pub quadric: usize,
    /// The ray, world space.
    pub ray: Ray,
    /// Largest accepted t.
    pub t_max: f64,
    /// The ray was spawned on this quadric (the renderer passes `from_self`).
    pub from_self: bool,
}

/// A named family of hard cases.
#[derive(Clone, Debug)]
pub struct Family {
    /// Short name for tables.
    pub name: &'static str,
    /// What the family exercises (catalogue number and geometry).
    pub about: &'static str,
    /// The quadrics the cases refer to.
    pub quadrics: Vec<Quadric>,
    /// The rays.
    pub cases: Vec<Case>,
}

/// Parameters of a whole suite: how many rays per family and kind, and the random seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SuiteSize {
    /// Rays per (family, quadric) pair, roughly.
    pub rays: usize,
    /// Seed of every generator.
    pub seed: u64,
}

impl SuiteSize {
    /// The size `cargo test` runs.
    pub const TEST: SuiteSize = SuiteSize { rays: 120, seed: 7 };
    /// The size `quadray bench accuracy` runs.
    pub const REPORT: SuiteSize = SuiteSize {
        rays: 1000,
        seed: 11,
    };
}

/// The quadric of `kind` with its parameters and clip box (object frame), placed by `transform`.
pub fn make(kind: QuadricKind, abc: [f64; 3], clip: ClipBox, transform: Transform) -> Quadric {
    Quadric::new(
        QuadricSurface::Canonical {
            kind,
            a: abc[0],
            b: abc[1],
            c: abc[2],
        },
        clip,
        transform,
        0,
    )
    .expect("hard-case quadrics are valid")
}

/// The standard member of each kind: unequal axes, an off-centre clip box that cuts the surface.
pub fn standard(kind: QuadricKind, transform: Transform) -> Quadric {
    make(
        kind,
        [0.8, 1.0, 0.6],
        ClipBox {
            min: DVec3::new(-1.3, -1.4, -1.1),
            max: DVec3::new(1.4, 1.2, 1.3),
        },
        transform,
    )
}

/// A fixed, unremarkable rotation and translation, scaled by `s`, then moved by `shift`.
pub fn placement(s: f64, shift: DVec3) -> Transform {
    let base = Transform::from_srt(
        DVec3::splat(s),
        DVec3::new(20.0, -30.0, 40.0),
        DVec3::new(0.3, -0.2, 0.1) * s + shift,
    )
    .expect("valid placement");
    Transform::new(base.to_world).expect("valid placement")
}

fn unit(rng: &mut StdRng) -> DVec3 {
    loop {
        let v = DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let l = v.length_squared();
        if l > 1e-6 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

fn in_bounds(rng: &mut StdRng, (lo, hi): (DVec3, DVec3), grow: f64) -> DVec3 {
    let c = (lo + hi) * 0.5;
    let h = (hi - lo) * 0.5 * grow;
    c + h * DVec3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    )
}

fn size(q: &Quadric) -> f64 {
    let (lo, hi) = q.bounds();
    (hi - lo).length() * 0.5
}

fn centre(q: &Quadric) -> DVec3 {
    let (lo, hi) = q.bounds();
    (lo + hi) * 0.5
}

fn aim(origin: DVec3, target: DVec3) -> Ray {
    Ray::new(origin, (target - origin).normalize())
}

fn case(quadric: usize, ray: Ray) -> Case {
    Case {
        quadric,
        ray,
        t_max: f64::INFINITY,
        from_self: false,
    }
}

/// Surface points with unit normals, found by shooting rays at the quadric from around it.
pub fn surface_points(q: &Quadric, rng: &mut StdRng, count: usize) -> Vec<(DVec3, DVec3)> {
    let mut out = Vec::with_capacity(count);
    let (c, s) = (centre(q), size(q));
    for _ in 0..count * 50 {
        if out.len() == count {
            break;
        }
        let ray = aim(c + unit(rng) * 4.0 * s, in_bounds(rng, q.bounds(), 0.9));
        if let Some(t) = q.intersect(&ray, f64::INFINITY, false) {
            let g = q.surface(&ray, t);
            out.push((g.point, g.geometric_normal));
        }
    }
    out
}

/// Rays from `origin_of(i)` to random points of the quadric's bounds, `n` of them per quadric.
fn shoot(
    quadrics: &[Quadric],
    rng: &mut StdRng,
    n: usize,
    mut origin_of: impl FnMut(&Quadric, &mut StdRng) -> DVec3,
) -> Vec<Case> {
    let mut cases = Vec::new();
    for (i, q) in quadrics.iter().enumerate() {
        for _ in 0..n {
            let o = origin_of(q, rng);
            cases.push(case(i, aim(o, in_bounds(rng, q.bounds(), 1.1))));
        }
    }
    cases
}

fn all_kinds(transform: Transform) -> Vec<Quadric> {
    QuadricKind::ALL
        .iter()
        .map(|&k| standard(k, transform))
        .collect()
}

/// Families 3–4 from production hits of `base`: for each of `hits` hit points per quadric, `dirs`
/// rays leaving the surface in uniformly random directions (either side), offset by the hit's error
/// bound and flagged as spawned (so the concave re-hits of family 4 are included).
pub fn spawned(base: &Family, hits: usize, dirs: usize, seed: u64) -> Family {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut cases = Vec::new();
    let mut found = vec![0usize; base.quadrics.len()];
    for c in &base.cases {
        if found[c.quadric] == hits {
            continue;
        }
        let q = &base.quadrics[c.quadric];
        let Some(t) = q.intersect(&c.ray, c.t_max, c.from_self) else {
            continue;
        };
        found[c.quadric] += 1;
        let g = q.surface(&c.ray, t);
        for _ in 0..dirs {
            let w = unit(&mut rng);
            let o = quadray::math::offset_origin(g.point, g.geometric_normal, g.error, w);
            cases.push(Case {
                quadric: c.quadric,
                ray: Ray::new(o, w),
                t_max: f64::INFINITY,
                from_self: true,
            });
        }
    }
    Family {
        name: base.name,
        about: base.about,
        quadrics: base.quadrics.clone(),
        cases,
    }
}

/// Every intersection family of the catalogue (the spawned-ray families are derived per family).
pub fn all(size_: SuiteSize) -> Vec<Family> {
    let shift = DVec3::new(1e6, -1e6, 1e6);
    vec![
        scene(size_, 1.0, DVec3::ZERO, "scene-1"),
        scene(size_, 1e-6, DVec3::ZERO, "scene-1e-6"),
        scene(size_, 1e6, DVec3::ZERO, "scene-1e6"),
        scene(size_, 1.0, shift, "scene-moved-1e6"),
        far(size_),
        huge(size_),
        axis_parallel(size_, 0.0),
        axis_parallel(size_, 1e-6),
        asymptote(size_),
        apex(size_),
        tangent(size_),
        inside(size_),
        negative_a(size_),
        open_cup(size_),
        clip_face(size_),
        waist(size_),
        thin_ellipsoid(size_),
    ]
}
