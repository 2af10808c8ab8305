//! The intersection families of the catalogue (quadric-numerics.md §4), one generator each: the
//! quadrics of every kind a family applies to, and rays aimed at what makes it hard.

use super::*;

/// Family 1: every kind seen from 10⁸ away, rays across silhouettes and rims.
pub fn far(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 1);
    let quadrics = all_kinds(placement(1.0, DVec3::ZERO));
    let cases = shoot(&quadrics, &mut rng, size_.rays, |q, rng| {
        centre(q) + unit(rng) * 1e8
    });
    Family {
        name: "far-1e8",
        about: "§4.1: unit-size quadrics of every kind seen from 1e8 away, rays across the silhouette",
        quadrics,
        cases,
    }
}

/// Family 2: every kind at planetary scale (6.4e6), camera one unit above the surface.
pub fn huge(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 2);
    let quadrics = all_kinds(placement(6.4e6, DVec3::ZERO));
    let mut cases = Vec::new();
    for (i, q) in quadrics.iter().enumerate() {
        let points = surface_points(q, &mut rng, 8);
        for k in 0..size_.rays {
            let Some(&(p, n)) = points.get(k % points.len().max(1)) else {
                break;
            };
            // One unit above the surface (on either side), looking back down at it.
            let side = if k % 2 == 0 { 1.0 } else { -1.0 };
            let o = p + n * side;
            let mut w = unit(&mut rng);
            if w.dot(n) * side > 0.0 {
                w = -w;
            }
            cases.push(case(i, Ray::new(o, w)));
        }
    }
    Family {
        name: "huge-6.4e6",
        about: "§4.2: every kind scaled to radius 6.4e6, camera one unit above the surface",
        quadrics,
        cases,
    }
}

/// Families 5–6: rays exactly and nearly parallel to the object axes (a = 0 or a ≈ 1e-12·β).
pub fn axis_parallel(size_: SuiteSize, tilt: f64) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 5 ^ tilt.to_bits());
    // Identity placement keeps the directions exactly axial in the object frame.
    let quadrics = all_kinds(Transform::IDENTITY);
    let mut cases = Vec::new();
    for (i, q) in quadrics.iter().enumerate() {
        for k in 0..size_.rays {
            let axis = k % 3;
            let sign = if (k / 3) % 2 == 0 { 1.0 } else { -1.0 };
            let mut d = DVec3::ZERO;
            d[axis] = sign;
            if tilt > 0.0 {
                let e = unit(&mut rng) * tilt;
                d += e - d * d.dot(e);
            }
            let mut o = in_bounds(&mut rng, q.bounds(), 1.05);
            o[axis] = -sign * 5.0;
            cases.push(case(i, Ray::new(o, d)));
        }
    }
    Family {
        name: if tilt == 0.0 {
            "axis-parallel"
        } else {
            "near-parallel"
        },
        about: if tilt == 0.0 {
            "§4.5: rays exactly parallel to an object axis (a = 0 for paraboloids and cylinders)"
        } else {
            "§4.6: rays tilted 1e-6 from an object axis (a ≈ 1e-12 of the other coefficients)"
        },
        quadrics,
        cases,
    }
}

/// Family 7: rays exactly along a generator or asymptote direction (a = 0 exactly) and 1e-7 off it.
pub fn asymptote(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 7);
    let kinds = [
        (QuadricKind::Cone, DVec3::new(1.0, 0.0, 1.0)),
        (QuadricKind::Hyperboloid1, DVec3::new(0.0, 1.0, 1.0)),
        (QuadricKind::Hyperboloid2, DVec3::new(1.0, 0.0, -1.0)),
        (QuadricKind::HyperbolicCylinder, DVec3::new(1.0, 1.0, 0.0)),
        (
            QuadricKind::HyperbolicParaboloid,
            DVec3::new(1.0, -1.0, 0.0),
        ),
    ];
    // Unit parameters make x² − z² etc. vanish exactly along (1, 0, 1).
    let quadrics: Vec<Quadric> = kinds
        .iter()
        .map(|&(k, _)| make(k, [1.0; 3], ClipBox::cube(1.5), Transform::IDENTITY))
        .collect();
    let mut cases = Vec::new();
    for (i, &(_, dir)) in kinds.iter().enumerate() {
        for k in 0..size_.rays {
            let d = if k % 2 == 0 {
                dir
            } else {
                dir + unit(&mut rng) * 1e-7
            };
            let target = in_bounds(&mut rng, quadrics[i].bounds(), 1.0);
            cases.push(case(i, Ray::new(target - d * 4.0, d)));
        }
    }
    Family {
        name: "asymptote",
        about: "§4.7: rays along a cone generator or hyperboloid/saddle asymptote (a = 0) and 1e-7 off",
        quadrics,
        cases,
    }
}

/// Family 8: rays passing 10⁻ᵏ from a cone's apex (k = 0..15) and exactly through it.
pub fn apex(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 8);
    let quadrics = vec![
        make(
            QuadricKind::Cone,
            [0.7, 1.0, 0.9],
            ClipBox::cube(1.0),
            Transform::IDENTITY,
        ),
        make(
            QuadricKind::Cone,
            [0.7, 1.0, 0.9],
            ClipBox::cube(1.0),
            placement(1.0, DVec3::ZERO),
        ),
    ];
    let mut cases = Vec::new();
    for (i, q) in quadrics.iter().enumerate() {
        let apex = q.transform().to_world.translation;
        for k in 0..size_.rays {
            let d = unit(&mut rng);
            let miss = if k % 17 == 16 {
                0.0
            } else {
                10f64.powi(-((k % 17) as i32))
            };
            let side = unit(&mut rng);
            let off = (side - d * d.dot(side)).normalize_or_zero() * miss;
            cases.push(case(i, Ray::new(apex + off - d * 3.0, d)));
        }
    }
    Family {
        name: "cone-apex",
        about: "§4.8: rays through a cone's apex and 1e-16..1 beside it",
        quadrics,
        cases,
    }
}

/// Family 9: tangent sweep, signed miss distances ±10⁻ᵏ (k = 1..15) from surface points of every kind.
pub fn tangent(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 9);
    let quadrics = all_kinds(placement(1.0, DVec3::ZERO));
    let mut cases = Vec::new();
    for (i, q) in quadrics.iter().enumerate() {
        let points = surface_points(q, &mut rng, size_.rays.div_ceil(30).max(1));
        let s = size(q);
        for (p, n) in points {
            for k in 1..=15 {
                for side in [1.0, -1.0] {
                    let w = unit(&mut rng);
                    let Some(tan) = (w - n * n.dot(w)).try_normalize() else {
                        continue;
                    };
                    let o = p + n * (side * s * 10f64.powi(-k)) - tan * (3.0 * s);
                    cases.push(case(i, Ray::new(o, tan)));
                }
            }
        }
    }
    Family {
        name: "tangent",
        about: "§4.9: tangent sweep, miss distances ±1e-1..1e-15 of the object size",
        quadrics,
        cases,
    }
}

/// Family 10: camera inside closed or cup-shaped surfaces, random directions.
pub fn inside(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 10);
    let t = placement(1.0, DVec3::ZERO);
    let inner = [
        (QuadricKind::Ellipsoid, DVec3::new(0.1, -0.2, 0.05)),
        (QuadricKind::EllipticCylinder, DVec3::new(0.2, 0.1, 0.7)),
        (QuadricKind::Hyperboloid2, DVec3::new(0.0, 0.1, 0.9)),
        (QuadricKind::EllipticParaboloid, DVec3::new(0.05, 0.0, 0.8)),
        (QuadricKind::Hyperboloid1, DVec3::new(0.1, 0.0, 0.0)),
    ];
    let quadrics: Vec<Quadric> = inner.iter().map(|&(k, _)| standard(k, t)).collect();
    let mut cases = Vec::new();
    for (i, &(_, p)) in inner.iter().enumerate() {
        let o = t.to_world.transform_point3(p);
        for _ in 0..size_.rays {
            cases.push(case(i, Ray::new(o, unit(&mut rng))));
        }
    }
    Family {
        name: "inside",
        about: "§4.10: camera inside an ellipsoid, cylinder, hyperboloid sheet or paraboloid cup",
        quadrics,
        cases,
    }
}

/// Family 11: kinds with an indefinite A, rays chosen so the leading coefficient a is negative.
pub fn negative_a(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 11);
    let t = placement(1.0, DVec3::ZERO);
    let kinds = [
        QuadricKind::Hyperboloid1,
        QuadricKind::Hyperboloid2,
        QuadricKind::Cone,
        QuadricKind::HyperbolicCylinder,
        QuadricKind::HyperbolicParaboloid,
    ];
    let quadrics: Vec<Quadric> = kinds.iter().map(|&k| standard(k, t)).collect();
    let mut cases = Vec::new();
    for (i, q) in quadrics.iter().enumerate() {
        let (a_obj, _, _) = q.surface_description().coefficients().to_matrix_form();
        let lin = t.from_world.matrix3;
        let mut made = 0;
        while made < size_.rays {
            let o = centre(q) + unit(&mut rng) * 4.0 * size(q);
            let ray = aim(o, in_bounds(&mut rng, q.bounds(), 1.0));
            let d = lin * ray.dir;
            if d.dot(a_obj * d) < 0.0 {
                cases.push(case(i, ray));
                made += 1;
            }
        }
    }
    Family {
        name: "negative-a",
        about: "§4.11: hyperboloids, cone, hyperbolic cylinder and saddle with a < 0 (root order)",
        quadrics,
        cases,
    }
}

/// Family 12: looking into open cups through their clip opening, so the near root is clipped away.
pub fn open_cup(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 12);
    let t = placement(1.0, DVec3::ZERO);
    let kinds = [
        QuadricKind::EllipticCylinder,
        QuadricKind::EllipticParaboloid,
        QuadricKind::Cone,
        QuadricKind::Hyperboloid1,
        QuadricKind::ParabolicCylinder,
    ];
    let clip = ClipBox {
        min: DVec3::new(-2.0, -2.0, -0.8),
        max: DVec3::new(2.0, 2.0, 0.9),
    };
    let quadrics: Vec<Quadric> = kinds
        .iter()
        .map(|&k| make(k, [0.8, 1.0, 0.6], clip, t))
        .collect();
    let mut cases = Vec::new();
    for (i, _) in kinds.iter().enumerate() {
        for _ in 0..size_.rays {
            // Above the top opening, aimed down through it at the inside of the far wall.
            let top = DVec3::new(
                rng.random_range(-0.5..0.5),
                rng.random_range(-0.5..0.5),
                0.9,
            );
            let from = DVec3::new(
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                4.0,
            );
            let o = t.to_world.transform_point3(from);
            let through = t.to_world.transform_point3(top);
            cases.push(case(i, aim(o, through)));
        }
    }
    Family {
        name: "open-cup",
        about: "§4.12: looking into open cylinders, paraboloids, cones through the clip opening",
        quadrics,
        cases,
    }
}

/// Family 13: hits within 10⁻ᵏ of a clip face (k = 1..15) along the rims of every kind.
pub fn clip_face(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 13);
    let t = placement(1.0, DVec3::ZERO);
    let quadrics = all_kinds(t);
    let mut cases = Vec::new();
    for (i, q) in quadrics.iter().enumerate() {
        let k = q.surface_description().coefficients();
        let clip = q.clip();
        let mut made = 0;
        let mut tries = 0;
        while made < size_.rays && tries < size_.rays * 100 {
            tries += 1;
            // A rim point: on a random face of the box, along a random line in it, where f = 0.
            let axis = rng.random_range(0..3usize);
            let face = if rng.random::<bool>() {
                clip.max[axis]
            } else {
                clip.min[axis]
            };
            let mut p = DVec3::new(
                rng.random_range(clip.min.x..clip.max.x),
                rng.random_range(clip.min.y..clip.max.y),
                rng.random_range(clip.min.z..clip.max.z),
            );
            p[axis] = face;
            let mut w = unit(&mut rng);
            w[axis] = 0.0;
            let (a, b, _) = k.to_matrix_form();
            let roots = quadray::math::solve_quadratic(w.dot(a * w), w.dot(a * p + b), k.eval(p));
            let Some(&s) = roots.as_slice().first() else {
                continue;
            };
            let mut rim = p + w * s;
            if (rim - rim.clamp(clip.min, clip.max)).abs().max_element() > 0.0 {
                continue;
            }
            let offset = 10f64.powi(-((made % 15) as i32 + 1));
            rim[axis] += if made % 2 == 0 { offset } else { -offset };
            let target = t.to_world.transform_point3(rim);
            let o = target + unit(&mut rng) * 5.0;
            cases.push(case(i, aim(o, target)));
            made += 1;
        }
    }
    Family {
        name: "clip-face",
        about: "§4.13: hits 1e-1..1e-15 inside and outside a clip face, grazing the rims",
        quadrics,
        cases,
    }
}

/// Family 14: hyperboloid x² + y² − z² = J with the waist J shrinking from 1 to 1e-14 and then 0 (cone).
pub fn waist(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 14);
    let t = placement(1.0, DVec3::ZERO);
    let quadrics: Vec<Quadric> = (0..=8)
        .map(|k| {
            let j = if k == 8 { 0.0 } else { 10f64.powi(-2 * k) };
            Quadric::new(
                QuadricSurface::General(Coefficients([
                    1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -j,
                ])),
                ClipBox::cube(1.0),
                t,
                0,
            )
            .expect("waist quadrics are valid")
        })
        .collect();
    let per = size_.rays.div_ceil(2).max(1);
    let cases = shoot(&quadrics, &mut rng, per, |q, rng| {
        centre(q) + unit(rng) * 4.0
    });
    Family {
        name: "waist",
        about: "§4.14: hyperboloid waist 1 → 1e-14 → 0 (the cone), all through one sweep of rays",
        quadrics,
        cases,
    }
}

/// Family 15: ellipsoid with axes 1e-4 : 1 : 1e4 rotated 37°, clipped tightly and by a cube.
pub fn thin_ellipsoid(size_: SuiteSize) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 15);
    let t = Transform::from_srt(
        DVec3::ONE,
        DVec3::new(37.0, 37.0, 0.0),
        DVec3::new(1.0, 2.0, 3.0),
    )
    .expect("valid rotation");
    let axes = [1e-4, 1.0, 1e4];
    let tight = ClipBox {
        min: DVec3::new(-1.01e-4, -1.01, -0.9e4),
        max: DVec3::new(1.01e-4, 1.01, 1.01e4),
    };
    let quadrics = vec![
        make(QuadricKind::Ellipsoid, axes, tight, t),
        make(QuadricKind::Ellipsoid, axes, ClipBox::cube(1.01e4), t),
    ];
    let mut cases = Vec::new();
    for i in 0..quadrics.len() {
        for k in 0..size_.rays {
            // Targets on the ellipsoid's own extent (the cube is mostly empty), from near and far.
            let u = DVec3::new(
                rng.random_range(-1.2..1.2) * axes[0],
                rng.random_range(-1.2..1.2) * axes[1],
                rng.random_range(-1.0..1.0) * axes[2],
            );
            let target = t.to_world.transform_point3(u);
            let dist = if k % 2 == 0 { 3.0 } else { 3e4 };
            cases.push(case(i, aim(target + unit(&mut rng) * dist, target)));
        }
    }
    Family {
        name: "thin-ellipsoid",
        about: "§4.15: ellipsoid 1e-4 : 1 : 1e4 rotated 37°, clipped tightly and by a 1e4 cube",
        quadrics,
        cases,
    }
}

/// Families 16–17: one scene of every kind, at scale `s`, moved by `shift`, seen from 5 sizes away
/// with the same random numbers at every scale, so counts can be compared one to one.
pub fn scene(size_: SuiteSize, s: f64, shift: DVec3, name: &'static str) -> Family {
    let mut rng = StdRng::seed_from_u64(size_.seed ^ 16);
    let quadrics = all_kinds(placement(s, shift));
    let cases = shoot(&quadrics, &mut rng, size_.rays, |q, rng| {
        centre(q) + unit(rng) * 5.0 * size(q)
    });
    Family {
        name,
        about: "§4.16–17: the same scene of every kind scaled by 1e-6 or 1e6, or moved 1e6 away",
        quadrics,
        cases,
    }
}
