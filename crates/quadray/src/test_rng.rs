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
