//! The number fields the oracle computes in ([`Field`]): exact binary rationals ([`Dyadic`], over
//! `num-bigint`, with divisions and square roots carried to [`EXACT_BITS`] bits) and double-double
//! (`twofloat::TwoFloat`, about 106 bits).

use super::EXACT_BITS;
use num_bigint::BigInt;
use num_traits::{Signed, ToPrimitive, Zero};
use std::cmp::Ordering;
use twofloat::TwoFloat;

/// The arithmetic the oracle needs: exact ring operations (or as good as the tier allows), and
/// division and square root to the tier's precision.
pub trait Field: Clone + std::fmt::Debug {
    /// The exact value of an f64.
    fn of(x: f64) -> Self;
    /// Sum.
    fn add(&self, o: &Self) -> Self;
    /// Difference.
    fn sub(&self, o: &Self) -> Self;
    /// Product.
    fn mul(&self, o: &Self) -> Self;
    /// Quotient, to the tier's precision.
    fn div(&self, o: &Self) -> Self;
    /// Square root of a non-negative value, to the tier's precision.
    fn sqrt(&self) -> Self;
    /// Sign: −1, 0 or 1.
    fn sign(&self) -> i32;
    /// Nearest f64 (within one ulp).
    fn to_f64(&self) -> f64;
    /// Negation.
    fn neg(&self) -> Self {
        Self::of(0.0).sub(self)
    }
}

/// An exact binary rational m·2^e.
#[derive(Clone, Debug)]
pub struct Dyadic {
    m: BigInt,
    e: i64,
}

impl Dyadic {
    /// Exponent alignment: both mantissas over the smaller exponent.
    fn aligned(&self, o: &Self) -> (BigInt, BigInt, i64) {
        match self.e.cmp(&o.e) {
            Ordering::Equal => (self.m.clone(), o.m.clone(), self.e),
            Ordering::Less => (self.m.clone(), &o.m << ((o.e - self.e) as usize), self.e),
            Ordering::Greater => (&self.m << ((self.e - o.e) as usize), o.m.clone(), o.e),
        }
    }
}

/// 2^e as f64, saturating to 0 or ∞ outside the range (applied in steps so subnormals come out right).
fn pow2(x: f64, e: i64) -> f64 {
    let mut x = x;
    let mut e = e;
    while e > 1000 {
        x *= 2f64.powi(1000);
        e -= 1000;
        if x.is_infinite() {
            return x;
        }
    }
    while e < -1000 {
        x *= 2f64.powi(-1000);
        e += 1000;
        if x == 0.0 {
            return x;
        }
    }
    x * 2f64.powi(e as i32)
}

impl Field for Dyadic {
    fn of(x: f64) -> Self {
        assert!(x.is_finite(), "oracle input {x} is not finite");
        if x == 0.0 {
            return Dyadic {
                m: BigInt::zero(),
                e: 0,
            };
        }
        // x = ±mantissa·2^(exponent − 1075) for the 52-bit stored mantissa with its hidden bit.
        let bits = x.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i64;
        let frac = bits & ((1u64 << 52) - 1);
        let (mant, e) = if exp == 0 {
            (frac, -1074)
        } else {
            (frac | (1u64 << 52), exp - 1075)
        };
        let m = BigInt::from(mant);
        Dyadic {
            m: if x < 0.0 { -m } else { m },
            e,
        }
    }

    fn add(&self, o: &Self) -> Self {
        let (a, b, e) = self.aligned(o);
        Dyadic { m: a + b, e }
    }

    fn sub(&self, o: &Self) -> Self {
        let (a, b, e) = self.aligned(o);
        Dyadic { m: a - b, e }
    }

    fn mul(&self, o: &Self) -> Self {
        Dyadic {
            m: &self.m * &o.m,
            e: self.e + o.e,
        }
    }

    fn div(&self, o: &Self) -> Self {
        assert!(!o.m.is_zero(), "oracle division by zero");
        // Shift the numerator so the integer quotient keeps EXACT_BITS significant bits (truncated).
        let shift = (EXACT_BITS + o.m.bits()).saturating_sub(self.m.bits()) + 2;
        let num = &self.m << (shift as usize);
        Dyadic {
            m: num / &o.m,
            e: self.e - o.e - shift as i64,
        }
    }

    fn sqrt(&self) -> Self {
        assert!(
            !self.m.is_negative(),
            "oracle square root of a negative number"
        );
        if self.m.is_zero() {
            return self.clone();
        }
        // m·2^e with e even and m of at least 2·EXACT_BITS bits: √ = isqrt(m)·2^(e/2).
        let mut shift = (2 * EXACT_BITS).saturating_sub(self.m.bits()) as i64 + 2;
        if (self.e - shift) % 2 != 0 {
            shift += 1;
        }
        let m = &self.m << (shift as usize);
        Dyadic {
            m: m.sqrt(),
            e: (self.e - shift) / 2,
        }
    }

    fn sign(&self) -> i32 {
        if self.m.is_zero() {
            0
        } else if self.m.is_negative() {
            -1
        } else {
            1
        }
    }

    fn to_f64(&self) -> f64 {
        if self.m.is_zero() {
            return 0.0;
        }
        // Keep the top 64 bits (truncated), then one rounding to f64: within one ulp.
        let bits = self.m.bits();
        let drop = bits.saturating_sub(64);
        let top = (self.m.abs() >> (drop as usize))
            .to_u64()
            .unwrap_or(u64::MAX) as f64;
        let v = pow2(top, self.e + drop as i64);
        if self.m.is_negative() { -v } else { v }
    }
}

impl Field for TwoFloat {
    fn of(x: f64) -> Self {
        TwoFloat::from(x)
    }
    fn add(&self, o: &Self) -> Self {
        *self + *o
    }
    fn sub(&self, o: &Self) -> Self {
        *self - *o
    }
    fn mul(&self, o: &Self) -> Self {
        *self * *o
    }
    fn div(&self, o: &Self) -> Self {
        *self / *o
    }
    fn sqrt(&self) -> Self {
        if self.hi() <= 0.0 {
            TwoFloat::from(0.0)
        } else {
            TwoFloat::sqrt(*self)
        }
    }
    fn sign(&self) -> i32 {
        let h = self.hi();
        if h > 0.0 {
            1
        } else if h < 0.0 {
            -1
        } else {
            0
        }
    }
    fn to_f64(&self) -> f64 {
        self.hi() + self.lo()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dyadic_is_exact_for_sums_and_products() {
        let x = Dyadic::of(0.1);
        let y = Dyadic::of(1e20);
        // (0.1 + 1e20) − 1e20 is exactly 0.1 in exact arithmetic (0 in f64).
        assert_eq!(x.add(&y).sub(&y).to_f64(), 0.1);
        assert_eq!(Dyadic::of(3.0).mul(&Dyadic::of(-0.5)).to_f64(), -1.5);
        assert_eq!(Dyadic::of(2.0).sqrt().to_f64(), 2f64.sqrt());
        assert_eq!(Dyadic::of(1.0).div(&Dyadic::of(3.0)).to_f64(), 1.0 / 3.0);
        assert_eq!(Dyadic::of(5e-324).to_f64(), 5e-324);
        assert_eq!(Dyadic::of(-1.7e308).to_f64(), -1.7e308);
    }
}
