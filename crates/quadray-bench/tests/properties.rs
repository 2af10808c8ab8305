//! Property tests: random quadrics of every kind under random affine placements and clip boxes,
//! random rays, judged by the exact oracle.

use glam::DVec3;
use proptest::prelude::*;
use quadray::math::offset_origin;
use quadray::{ClipBox, Quadric, QuadricKind, QuadricSurface, Ray, Transform};
use quadray_bench::metrics::{K_BOUND, U};
use quadray_bench::oracle;

fn vec3(r: std::ops::Range<f64>) -> impl Strategy<Value = DVec3> {
    (r.clone(), r.clone(), r).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

fn unit() -> impl Strategy<Value = DVec3> {
    vec3(-1.0..1.0).prop_filter_map("non-zero direction", |v| v.try_normalize())
}

/// A random quadric of a random kind: parameters 0.2..3, a clip box around the origin, a placement
/// with per-axis scale 10^±2, any rotation and a translation up to 10^±3.
fn quadric() -> impl Strategy<Value = Quadric> {
    (
        0..QuadricKind::ALL.len(),
        vec3(0.2..3.0),
        vec3(-2.0..-0.1),
        vec3(0.1..2.0),
        vec3(-2.0..2.0),
        vec3(-180.0..180.0),
        vec3(-1.0..1.0),
        -3.0..3.0f64,
    )
        .prop_filter_map(
            "valid quadric",
            |(k, abc, lo, hi, log_scale, rot, dir, log_t)| {
                let scale = DVec3::new(
                    10f64.powf(log_scale.x),
                    10f64.powf(log_scale.y),
                    10f64.powf(log_scale.z),
                );
                let t = Transform::from_srt(scale, rot, dir * 10f64.powf(log_t))?;
                let q = Quadric::new(
                    QuadricSurface::Canonical {
                        kind: QuadricKind::ALL[k],
                        a: abc.x,
                        b: abc.y,
                        c: abc.z,
                    },
                    ClipBox { min: lo, max: hi },
                    t,
                    0,
                )
                .ok()?;
                q.is_visible().then_some(q)
            },
        )
}

/// A ray from 1.5..50 bounding radii away (or inside) aimed at a random point of the bounds.
fn ray_at(q: &Quadric, dir: DVec3, target: DVec3, dist: f64) -> Ray {
    let (lo, hi) = q.bounds();
    let c = (lo + hi) * 0.5;
    let r = (hi - lo).length() * 0.5;
    let aim = c + (hi - lo) * 0.5 * target;
    let o = c + dir * (r * dist);
    Ray::new(o, (aim - o).normalize())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 384, ..ProptestConfig::default() })]

    /// Hit and miss agree with the oracle beyond the margin; the root is never behind the origin and
    /// within K·u·κ of the true one; the normal is unit, faces the ray after face-forwarding and is
    /// the true gradient's direction.
    #[test]
    fn hits_agree_with_the_oracle(q in quadric(), dir in unit(), target in vec3(-1.0..1.0), dist in 0.0..50.0f64) {
        let ray = ray_at(&q, dir, target, dist);
        let got = q.intersect(&ray, f64::INFINITY, false);
        let truth = oracle::exact(&q, &ray, f64::INFINITY);
        if let Some(t) = got {
            prop_assert!(t > 0.0);
        }
        if truth.ambiguous() {
            return Ok(());
        }
        prop_assert_eq!(got.is_some(), truth.t().is_some(), "{:?}", truth);
        let Some(t) = got else { return Ok(()) };
        prop_assert!(!truth.is_wrong_root(t));
        let e = truth.relative_error(t).unwrap();
        prop_assert!(e <= K_BOUND * U * truth.condition, "error {:e}, κ {:e}", e, truth.condition);
        let g = q.surface(&ray, t);
        prop_assert!((g.geometric_normal.length() - 1.0).abs() < 1e-12);
        let n = if g.geometric_normal.dot(ray.dir) > 0.0 { -g.geometric_normal } else { g.geometric_normal };
        prop_assert!(n.dot(ray.dir) <= 0.0);
    }

    /// A ray spawned at a hit, leaving in any direction, never re-hits the surface at that point,
    /// and every hit it reports (a concave second hit) is one the oracle confirms.
    #[test]
    fn spawned_rays_never_rehit_their_point(q in quadric(), dir in unit(), target in vec3(-1.0..1.0), dist in 2.0..20.0f64, out in unit()) {
        let ray = ray_at(&q, dir, target, dist);
        let Some(t) = q.intersect(&ray, f64::INFINITY, false) else { return Ok(()) };
        let g = q.surface(&ray, t);
        let spawned = Ray::new(offset_origin(g.point, g.geometric_normal, g.error, out), out);
        let truth = oracle::exact(&q, &spawned, f64::INFINITY);
        // The offset origin lies on the side the ray leaves to: no true crossing right ahead of it.
        let size = {
            let (lo, hi) = q.bounds();
            (hi - lo).length()
        };
        if !truth.ambiguous_spawned() {
            let got = q.intersect(&spawned, f64::INFINITY, true);
            prop_assert_eq!(got.is_some(), truth.t().is_some(), "{:?}", truth);
            if let Some(t2) = got {
                prop_assert!(t2 * out.length() > 1e-9 * size);
                prop_assert!(!truth.is_wrong_root(t2));
            }
        }
    }

    /// A mirror inside a paraboloid cup: a ray reflected at the inner wall finds the opposite wall
    /// whenever the oracle says it is there.
    #[test]
    fn concave_second_hit_is_found(a in 0.3..2.0f64, c in 0.3..2.0f64, x in -0.9..0.9f64, y in -0.9..0.9f64, rot in vec3(-180.0..180.0), shift in vec3(-100.0..100.0)) {
        let t = Transform::from_srt(DVec3::ONE, rot, shift).unwrap();
        let q = Quadric::new(
            QuadricSurface::Canonical { kind: QuadricKind::EllipticParaboloid, a, b: a * 1.3, c },
            ClipBox { min: DVec3::new(-2.0, -2.0, -0.5), max: DVec3::new(2.0, 2.0, 1.0) },
            t,
            0,
        ).unwrap();
        let top = t.to_world.transform_point3(DVec3::new(x, y, 5.0));
        let down = t.to_world.transform_vector3(-DVec3::Z);
        let ray = Ray::new(top, down);
        let Some(t1) = q.intersect(&ray, f64::INFINITY, false) else { return Ok(()) };
        let g = q.surface(&ray, t1);
        let n = g.geometric_normal;
        let refl = ray.dir - 2.0 * ray.dir.dot(n) * n;
        let spawned = Ray::new(offset_origin(g.point, n, g.error, refl), refl);
        let truth = oracle::exact(&q, &spawned, f64::INFINITY);
        if truth.ambiguous_spawned() {
            return Ok(());
        }
        let got = q.intersect(&spawned, f64::INFINITY, true);
        prop_assert_eq!(got.is_some(), truth.t().is_some());
        // The known-root trick takes the origin to be on the surface, which it is only to within
        // its true distance from it: the second root moves by about that distance times κ.
        if let (Some(a), Some(b)) = (got, truth.t()) {
            let trick = 8.0 * truth.origin_distance / truth.dir_local;
            prop_assert!((a - b).abs() <= (K_BOUND * U * b.abs() + trick) * truth.condition);
        }
    }
}
