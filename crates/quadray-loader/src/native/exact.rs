//! Fixed-length arrays read exactly: serde reads `[f64; 3]` from a longer TOML array and drops
//! the rest without a word (`to = [0, 0, 0, 4]` was accepted), so vectors, quaternions, matrix
//! rows, resolutions and triangles are read as lists and checked for their length.

use serde::{Deserialize, Deserializer};

/// `N` values of `T`, read from a list of exactly `N`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Exact<T, const N: usize>(pub(super) [T; N]);

impl<'de, T: Deserialize<'de> + Copy, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let list = Vec::<T>::deserialize(d)?;
        let values: [T; N] = list.as_slice().try_into().map_err(|_| {
            serde::de::Error::custom(format!(
                "expected a list of exactly {N} values, got {}",
                list.len()
            ))
        })?;
        Ok(Exact(values))
    }
}
