//! The unit tests' pseudo-random numbers: Marsaglia's xorshift64, seeded per test, so every test
//! draws the same values on every run.

/// Advances `state` one xorshift64 step (13, 7, 17) and returns it.
pub(crate) fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

/// A stream of numbers in [0, 1) from the top 53 bits of [`xorshift`] steps of `seed`.
pub(crate) fn unit_stream(mut seed: u64) -> impl FnMut() -> f64 {
    move || (xorshift(&mut seed) >> 11) as f64 / (1u64 << 53) as f64
}

/// A stream of numbers in [−0.5, 0.5) ([`unit_stream`] less a half).
pub(crate) fn centred_stream(seed: u64) -> impl FnMut() -> f64 {
    let mut unit = unit_stream(seed);
    move || unit() - 0.5
}

/// A random square cone of directions `size` wide around a random centre, from `next` (a
/// [`centred_stream`]): the direction at `(a, b)` of [−1, 1]² across it, the corners at ±1.
pub(crate) fn square_cone(
    next: &mut dyn FnMut() -> f64,
    size: f64,
) -> impl Fn(f64, f64) -> glam::DVec3 + use<> {
    let centre = glam::DVec3::new(next(), next(), next()).normalize_or(glam::DVec3::Z);
    let (e1, e2) = crate::math::orthonormal_basis(centre);
    move |a, b| centre + (e1 * a + e2 * b) * size
}

/// The rays from `eye` through the corners of `cone` ([`square_cone`]) in a tile's order: (left,
/// top), (right, top), (left, bottom), (right, bottom).
pub(crate) fn corner_rays(
    eye: glam::DVec3,
    cone: &impl Fn(f64, f64) -> glam::DVec3,
) -> [crate::math::Ray; 4] {
    [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
        .map(|(a, b)| crate::math::Ray::new(eye, cone(a, b)))
}
