//! Unit tests of quadrics: kinds, classification, hits, normals and the visible range.

use super::*;

fn quadric(kind: QuadricKind, a: f64, b: f64, c: f64, r: f64) -> Quadric {
    Quadric::new(
        QuadricSurface::Canonical { kind, a, b, c },
        ClipBox::cube(r),
        Transform::IDENTITY,
        0,
    )
    .unwrap()
}

fn gradient(k: &Coefficients, p: DVec3) -> DVec3 {
    let (a, b, _) = k.to_matrix_form();
    2.0 * (a * p + b)
}

#[test]
fn names_round_trip_and_classify_as_themselves() {
    for kind in QuadricKind::ALL {
        assert_eq!(QuadricKind::from_name(kind.name()), Some(kind));
        let q = quadric(kind, 0.7, 1.3, 0.9, 2.0);
        assert_eq!(q.class(), QuadricClass::Proper(kind), "{kind}");
    }
    assert_eq!(QuadricKind::from_name("torus"), None);
}

#[test]
fn classification_survives_rotation_and_translation() {
    let t = Transform::from_srt(
        DVec3::new(1.0, 2.0, 0.5),
        DVec3::new(20.0, -35.0, 70.0),
        DVec3::new(3.0, -1.0, 2.0),
    )
    .unwrap();
    for kind in QuadricKind::ALL {
        let q = Quadric::new(
            QuadricSurface::Canonical {
                kind,
                a: 1.0,
                b: 1.5,
                c: 0.5,
            },
            ClipBox {
                min: DVec3::new(-2.0, -1.0, -0.5),
                max: DVec3::new(1.0, 3.0, 2.0),
            },
            t,
            0,
        )
        .unwrap();
        assert_eq!(q.class(), QuadricClass::Proper(kind));
    }
}

#[test]
fn degenerate_inputs_are_classified_and_rejected() {
    let general = |k: [f64; 10]| {
        Quadric::new(
            QuadricSurface::General(Coefficients(k)),
            ClipBox::cube(2.0),
            Transform::IDENTITY,
            0,
        )
    };
    let e = |class| Err(QuadricError::Degenerate(class));
    assert_eq!(general([0.0; 10]), e(QuadricClass::AllZero));
    assert_eq!(
        general([1.0, 0., 0., 0., 0., 0., 0., 0., 0., 0.]),
        e(QuadricClass::DoublePlane)
    );
    assert_eq!(
        general([1.0, 1.0, 1.0, 0., 0., 0., 0., 0., 0., 1.0]),
        e(QuadricClass::Empty)
    );
    assert_eq!(
        general([1.0, 1.0, 1.0, 0., 0., 0., 0., 0., 0., 0.0]),
        e(QuadricClass::Point)
    );
    assert_eq!(
        general([0.0, 0.0, 0.0, 0., 0., 0., 1., 0., 0., 0.0]),
        e(QuadricClass::Plane)
    );
    assert_eq!(
        general([1.0, 1.0, 0.0, 0., 0., 0., 0., 0., 0., 0.0]),
        e(QuadricClass::Line)
    );
    let pair = general([1.0, 0., 0., 0., 0., 0., 0., 0., 0., -1.0]).unwrap();
    assert_eq!(pair.class(), QuadricClass::ParallelPlanes);
    let cross = general([1.0, -1.0, 0., 0., 0., 0., 0., 0., 0., 0.0]).unwrap();
    assert_eq!(cross.class(), QuadricClass::IntersectingPlanes);
}

#[test]
fn rejects_bad_parameters_and_boxes() {
    let ellipsoid = |a, b, c| QuadricSurface::Canonical {
        kind: QuadricKind::Ellipsoid,
        a,
        b,
        c,
    };
    let new = |s, clip| Quadric::new(s, clip, Transform::IDENTITY, 0);
    assert!(matches!(
        new(ellipsoid(-1.0, 1.0, 1.0), ClipBox::cube(1.0)),
        Err(QuadricError::BadParameter { name: "a", .. })
    ));
    assert!(new(ellipsoid(1.0, f64::NAN, 1.0), ClipBox::cube(1.0)).is_err());
    // Parameters whose 1/a² is not a normal f64, and clip boxes so far from the surface's scale
    // that its coefficients in the box's frame under- or overflow, are refused as such (they
    // were called "empty" or "all zero").
    for a in [1e-300, 1e300] {
        assert!(matches!(
            new(ellipsoid(a, 1.0, 1.0), ClipBox::cube(1.0)),
            Err(QuadricError::ParameterRange { name: "a", .. })
        ));
    }
    let unit = ellipsoid(1.0, 1.0, 1.0);
    for size in [1e-200, 1e300] {
        assert!(matches!(
            new(unit, ClipBox::cube(size)),
            Err(QuadricError::ClipScale { .. })
        ));
    }
    // The accuracy suite's scales stay well inside.
    for size in [1e-6, 1e6] {
        assert!(new(unit, ClipBox::cube(size)).is_ok());
    }
    let flat = ClipBox {
        min: DVec3::new(-1.0, -1.0, 0.0),
        max: DVec3::new(1.0, 1.0, 0.0),
    };
    assert!(matches!(
        new(unit, flat),
        Err(QuadricError::EmptyClipBox { .. })
    ));
}

#[test]
fn analytic_hits_per_kind() {
    let inf = f64::INFINITY;
    let down = |x: f64, y: f64| Ray::new(DVec3::new(x, y, 10.0), -DVec3::Z);
    let along_x = |y: f64, z: f64| Ray::new(DVec3::new(-10.0, y, z), DVec3::X);
    // Ellipsoid a=2,b=1,c=0.5 from above: z = 0.5.
    let q = quadric(QuadricKind::Ellipsoid, 2.0, 1.0, 0.5, 3.0);
    assert!((q.intersect(&down(0.0, 0.0), inf, false).unwrap() - 9.5).abs() < 1e-14);
    // From inside, the far wall.
    let inside = Ray::new(DVec3::ZERO, DVec3::X);
    assert!((q.intersect(&inside, inf, false).unwrap() - 2.0).abs() < 1e-14);
    // Hyperboloid of one sheet: waist radius 1 along x at z = 0 -> t = 9.
    let q = quadric(QuadricKind::Hyperboloid1, 1.0, 1.0, 1.0, 3.0);
    assert!((q.intersect(&along_x(0.0, 0.0), inf, false).unwrap() - 9.0).abs() < 1e-14);
    // Two sheets: vertex at z = c = 1 from above.
    let q = quadric(QuadricKind::Hyperboloid2, 1.0, 1.0, 1.0, 3.0);
    assert!((q.intersect(&down(0.0, 0.0), inf, false).unwrap() - 9.0).abs() < 1e-14);
    // Cone x²+y² = z²: at height z = 2 along x, x = -2 -> t = 8.
    let q = quadric(QuadricKind::Cone, 1.0, 1.0, 1.0, 3.0);
    assert!((q.intersect(&along_x(0.0, 2.0), inf, false).unwrap() - 8.0).abs() < 1e-14);
    // Elliptic cylinder a = 2: t = 8 along x.
    let q = quadric(QuadricKind::EllipticCylinder, 2.0, 1.0, 1.0, 3.0);
    assert!((q.intersect(&along_x(0.0, 0.5), inf, false).unwrap() - 8.0).abs() < 1e-14);
    // Hyperbolic cylinder x² − y² = 1: at y = 0, x = -1 -> t = 9.
    let q = quadric(QuadricKind::HyperbolicCylinder, 1.0, 1.0, 1.0, 3.0);
    assert!((q.intersect(&along_x(0.0, 0.0), inf, false).unwrap() - 9.0).abs() < 1e-14);
    // Parabolic cylinder z = x²: from above at x = 1 -> z = 1, t = 9.
    let q = quadric(QuadricKind::ParabolicCylinder, 1.0, 1.0, 1.0, 3.0);
    assert!((q.intersect(&down(1.0, 0.7), inf, false).unwrap() - 9.0).abs() < 1e-14);
    // Elliptic paraboloid exactly along its axis (a = 0 in the quadratic): vertex at t = 10.
    let q = quadric(QuadricKind::EllipticParaboloid, 1.0, 1.0, 1.0, 3.0);
    assert_eq!(q.intersect(&down(0.0, 0.0), inf, false), Some(10.0));
    // Saddle z = x² − y² at (1, 0.5): z = 0.75 -> t = 9.25.
    let q = quadric(QuadricKind::HyperbolicParaboloid, 1.0, 1.0, 1.0, 3.0);
    assert!((q.intersect(&down(1.0, 0.5), inf, false).unwrap() - 9.25).abs() < 1e-14);
}

#[test]
fn far_root_through_the_clip_opening() {
    // A paraboloid cup z = x² + y² clipped at |z| <= 1: looking down the axis at x = 0.5 the outer
    // wall (z = 0.25) is hit; looking in through the rim from the side, the near root is outside the
    // box and only the far wall counts.
    let q = quadric(QuadricKind::EllipticParaboloid, 1.0, 1.0, 1.0, 1.0);
    let r = Ray::new(DVec3::new(-3.0, 0.0, 0.9), DVec3::new(1.0, 0.0, 0.0));
    // Roots at x = ±√0.9 ≈ ±0.949, both inside the box: the near one wins.
    let t = q.intersect(&r, f64::INFINITY, false).unwrap();
    assert!((t - (3.0 - 0.9f64.sqrt())).abs() < 1e-14);
    // Through the top opening, aimed down and sideways: the near root lies above the box (z > 1).
    // Through (-0.5, 0, 1): backwards the line meets the paraboloid at x ≈ -3.1, z ≈ 9.7 (outside).
    let dir = DVec3::new(0.3, 0.0, -1.0);
    let o = DVec3::new(-0.5, 0.0, 1.0) - dir * 2.0;
    let r = Ray::new(o, dir);
    let t = q.intersect(&r, f64::INFINITY, false).unwrap();
    let p = r.at(t);
    assert!(p.z <= 1.0 && (p.z - (p.x * p.x + p.y * p.y)).abs() < 1e-12);
    assert!(p.x > -1.0, "hit the far inner wall, x = {}", p.x);
}

#[test]
fn normals_equal_normalised_gradient_and_finite_differences() {
    let t = Transform::from_srt(
        DVec3::new(1.5, 0.7, 1.2),
        DVec3::new(10.0, 20.0, 30.0),
        DVec3::new(0.5, -1.0, 2.0),
    )
    .unwrap();
    for kind in QuadricKind::ALL {
        let surface = QuadricSurface::Canonical {
            kind,
            a: 0.8,
            b: 1.1,
            c: 0.9,
        };
        let q = Quadric::new(surface, ClipBox::cube(1.5), t, 0).unwrap();
        let k = surface.coefficients();
        let mut hits = 0;
        for i in 0..40 {
            let ang = i as f64 * 0.7;
            let target = t.to_world.transform_point3(DVec3::new(
                ang.cos() * 1.1,
                ang.sin() * 0.4,
                1.2 * (i as f64 * 1.3).sin(),
            ));
            let from = target + DVec3::new(ang.sin(), 2.0, 1.0 + ang.cos()) * 6.0;
            let ray = Ray::new(from, (target - from).normalize());
            let Some(th) = q.intersect(&ray, f64::INFINITY, false) else {
                continue;
            };
            hits += 1;
            let s = q.surface(&ray, th);
            let p_obj = t.from_world.transform_point3(s.point);
            // Gradient in the object frame, mapped to world by the inverse transpose.
            let expected = (t.normal_to_world * gradient(&k, p_obj)).normalize();
            assert!(s.geometric_normal.dot(expected) > 1.0 - 1e-9, "{kind}");
            // Central differences of f in world coordinates.
            let fw = |p: DVec3| k.eval(t.from_world.transform_point3(p));
            let h = 1e-6;
            let fd = DVec3::new(
                fw(s.point + DVec3::X * h) - fw(s.point - DVec3::X * h),
                fw(s.point + DVec3::Y * h) - fw(s.point - DVec3::Y * h),
                fw(s.point + DVec3::Z * h) - fw(s.point - DVec3::Z * h),
            )
            .normalize();
            assert!(
                s.geometric_normal.dot(fd) > 1.0 - 1e-6,
                "{kind}: {} vs {}",
                s.geometric_normal,
                fd
            );
            assert!((s.geometric_normal.length() - 1.0).abs() < 1e-12);
        }
        assert!(hits > 5, "{kind}: only {hits} hits");
    }
}

#[test]
fn spawned_rays_never_self_hit_but_find_concave_second_hits() {
    // Inside a paraboloid cup a reflected ray crosses to the opposite wall.
    let q = quadric(QuadricKind::EllipticParaboloid, 1.0, 1.0, 1.0, 1.0);
    let r = Ray::new(DVec3::new(0.5, 0.0, 5.0), -DVec3::Z);
    let t = q.intersect(&r, f64::INFINITY, false).unwrap();
    let s = q.surface(&r, t);
    let n = s.geometric_normal;
    let refl = r.dir - 2.0 * r.dir.dot(n) * n;
    let spawned = Ray::new(crate::math::offset_origin(s.point, n, s.error, refl), refl);
    let t2 = q
        .intersect(&spawned, f64::INFINITY, true)
        .expect("concave second hit");
    assert!(t2 > 0.1);
    // Leaving the outside of an ellipsoid: no hit.
    let e = quadric(QuadricKind::Ellipsoid, 1.0, 2.0, 0.5, 3.0);
    let r = Ray::new(DVec3::new(0.1, 0.2, 5.0), -DVec3::Z);
    let t = e.intersect(&r, f64::INFINITY, false).unwrap();
    let s = e.surface(&r, t);
    let out = Ray::new(
        crate::math::offset_origin(s.point, s.geometric_normal, s.error, DVec3::Z),
        DVec3::Z,
    );
    assert_eq!(e.intersect(&out, f64::INFINITY, true), None);
}

#[test]
fn cone_apex_gets_a_finite_normal() {
    let q = quadric(QuadricKind::Cone, 1.0, 1.0, 1.0, 1.0);
    let r = Ray::new(DVec3::new(0.0, -5.0, 0.0), DVec3::Y);
    let t = q
        .intersect(&r, f64::INFINITY, false)
        .expect("the apex is on the surface");
    assert!((t - 5.0).abs() < 1e-12);
    let s = q.surface(&r, t);
    assert!(s.geometric_normal.is_finite() && (s.geometric_normal.length() - 1.0).abs() < 1e-12);
    assert!(s.error.is_finite());
}

#[test]
fn height_range_follows_the_visible_surface() {
    // Ellipsoid with c = 0.5 inside a cube of radius 2: the ramp spans z in [-0.5, 0.5].
    let q = quadric(QuadricKind::Ellipsoid, 1.0, 1.0, 0.5, 2.0);
    let (lo, hi) = q.height;
    assert!(
        (lo * 2.0 + 0.5).abs() < 1e-9 && (hi * 2.0 - 0.5).abs() < 1e-9,
        "{lo} {hi}"
    );
    // A cylinder spans the whole box.
    let q = quadric(QuadricKind::EllipticCylinder, 1.0, 1.0, 1.0, 2.0);
    assert_eq!(q.height, (-1.0, 1.0));
    // A sphere outside its box is invisible.
    let s = QuadricSurface::Canonical {
        kind: QuadricKind::Ellipsoid,
        a: 0.1,
        b: 0.1,
        c: 0.1,
    };
    let far = ClipBox {
        min: DVec3::splat(1.0),
        max: DVec3::splat(2.0),
    };
    assert!(
        !Quadric::new(s, far, Transform::IDENTITY, 0)
            .unwrap()
            .is_visible()
    );
}

#[test]
fn curvature_is_the_larger_principal_curvature() {
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9 * b.abs().max(1.0);
    // A sphere of radius 2 (an ellipsoid with equal axes), anywhere on it.
    let sphere = quadric(QuadricKind::Ellipsoid, 2.0, 2.0, 2.0, 3.0);
    for p in [
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, -2.0),
        DVec3::splat(2.0 / 3f64.sqrt()),
    ] {
        assert!(
            close(sphere.curvature(p), 0.5),
            "{p}: {}",
            sphere.curvature(p)
        );
    }
    // A cylinder of radius 0.5: 2 around it, 0 along it; the larger is 2.
    let cylinder = quadric(QuadricKind::EllipticCylinder, 0.5, 0.5, 1.0, 1.0);
    assert!(close(cylinder.curvature(DVec3::new(0.0, 0.5, 0.3)), 2.0));
    // An ellipsoid's tip on its long axis c: both curvatures c/a² there (here 4/1 = 4).
    let ellipsoid = quadric(QuadricKind::Ellipsoid, 1.0, 1.0, 4.0, 5.0);
    assert!(close(ellipsoid.curvature(DVec3::new(0.0, 0.0, 4.0)), 4.0));
    // Placed by a rotation and a translation, the sphere keeps its curvature; scaled by 3,
    // it has a third of it.
    let placed = Quadric::new(
        QuadricSurface::Canonical {
            kind: QuadricKind::Ellipsoid,
            a: 2.0,
            b: 2.0,
            c: 2.0,
        },
        ClipBox::cube(3.0),
        Transform::from_srt(
            DVec3::splat(3.0),
            DVec3::new(10.0, 20.0, 30.0),
            DVec3::new(1.0, 2.0, 3.0),
        )
        .unwrap(),
        0,
    )
    .unwrap();
    let on_it = DVec3::new(1.0, 2.0, 3.0 + 6.0);
    assert!(
        close(placed.curvature(on_it), 0.5 / 3.0),
        "{}",
        placed.curvature(on_it)
    );
    // The cone's apex has no normal: no curvature rather than NaN.
    let cone = quadric(QuadricKind::Cone, 1.0, 1.0, 1.0, 1.0);
    assert_eq!(cone.curvature(DVec3::ZERO), 0.0);
}

/// The cube interval folds its bounds as `f64::max` and `min` of the slab test's do: the same
/// interval (a zero's sign aside) on random rays, on rays in the plane of a face (a NaN bound),
/// along axes and with zero components of either sign, for infinite, short and zero `t_max`.
#[test]
fn cube_interval_folds_bounds_as_max_and_min_do() {
    let reference = |o: DVec3, d: DVec3, t_max: f64| {
        let (t_in, t_out) = crate::math::slab_interval(o, d, -DVec3::ONE, DVec3::ONE);
        (t_in.max(0.0), t_out.min(t_max))
    };
    let mut next = crate::test_rng::centred_stream(0x5eed_cafe);
    let mut coordinate = |pick: u64| match pick % 6 {
        0 => 1.0,
        1 => -1.0,
        2 => 0.0,
        3 => -0.0,
        _ => next() * 6.0,
    };
    let mut state = 0x1234_5678_u64;
    for _ in 0..20_000 {
        let mut pick = || crate::test_rng::xorshift(&mut state);
        let o = DVec3::new(coordinate(pick()), coordinate(pick()), coordinate(pick()));
        let d = DVec3::new(coordinate(pick()), coordinate(pick()), coordinate(pick()));
        for t_max in [f64::INFINITY, 0.5, 3.0, 0.0] {
            let (lo, hi) = unit_cube_interval(unit_cube_slabs(o, d), t_max);
            let (want_lo, want_hi) = reference(o, d, t_max);
            let same = |x: f64, y: f64| x == y || (x.is_nan() && y.is_nan());
            assert!(
                same(lo, want_lo) && same(hi, want_hi),
                "o {o}, d {d}, t_max {t_max}: {lo}..{hi}, want {want_lo}..{want_hi}"
            );
        }
    }
}

/// A hit below the limit is the hit an unbounded test finds, bit for bit, so traversals that test
/// shapes in different orders, with different limits reached, agree: on grazing rays of every
/// kind (origin a few units before a surface point, along a tangent, offset off the surface by
/// 10⁻³ to 10⁻¹² of the scale to either side, at scales 10⁻³ to 10³), with limits between the
/// unbounded hit and the point of tangency, where the step to the vertex of the ray's quadratic
/// (which lies beyond the limit) is taken.
#[test]
fn roots_do_not_depend_on_the_limit() {
    let mut next = crate::test_rng::centred_stream(0x7a9e_17c0);
    let (mut limited, mut cases) = (0, 0);
    for kind in QuadricKind::ALL {
        for scale in [1e-3, 1.0, 1e3] {
            let q = Quadric::new(
                QuadricSurface::Canonical {
                    kind,
                    a: 0.8,
                    b: 1.1,
                    c: 0.7,
                },
                ClipBox::cube(2.0),
                Transform::from_srt(
                    DVec3::splat(scale),
                    DVec3::new(10.0, -20.0, 35.0),
                    DVec3::new(0.3, -0.2, 0.1) * scale,
                )
                .unwrap(),
                0,
            )
            .unwrap();
            for _ in 0..400 {
                let target = DVec3::new(next(), next(), next()) * 2.0 * scale;
                let origin = target + DVec3::new(next(), next(), 3.0) * 9.0 * scale;
                let aim = Ray::new(origin, target - origin);
                let Some(t) = q.intersect(&aim, f64::INFINITY, false) else {
                    continue;
                };
                let s = q.surface(&aim, t);
                let n = s.geometric_normal;
                let tangent = n.cross(DVec3::new(next(), next(), next())).normalize();
                for offset in [1e-3, -1e-3, 1e-6, -1e-6, 1e-9, -1e-9, -1e-12] {
                    let length = (2.0 + next()) * scale;
                    let ray = Ray::new(s.point + n * (offset * scale) - tangent * length, tangent);
                    let unbounded = q.intersect(&ray, f64::INFINITY, false);
                    // Limits from just past the unbounded hit to the point of tangency.
                    let from = unbounded.unwrap_or(0.5 * length);
                    for k in 0..8 {
                        let t_max = from + (length - from) * (k as f64 / 8.0) + f64::EPSILON * from;
                        let want = unbounded.filter(|&t| t <= t_max);
                        assert_eq!(
                            q.intersect(&ray, t_max, false),
                            want,
                            "{kind} at scale {scale}, ray {ray:?}, t_max {t_max}"
                        );
                        limited += usize::from(want.is_some() && t_max < length);
                        cases += 1;
                    }
                }
            }
        }
    }
    // Many cases hit below a limit short of the point of tangency.
    assert!(limited * 10 > cases, "{limited} of {cases}");
}
