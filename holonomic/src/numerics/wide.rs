//! Numbers with a wider exponent than `f64`'s, for sums of products of finite numbers whose
//! intermediate results overflow `f64` although the result is needed only up to a limit.
//!
//! The controller computes its commands with `f64` and, when that overflows, again with
//! [`Wide`]: with α1 = 1.7e308 the term K11·α1 is infinite in `f64` (and K11·α1 − K13·α2 may be
//! inf − inf = NaN), but as a `Wide` it is an ordinary number far beyond ±M_max, so the limited
//! command is right. Each operation rounds like `f64` (one rounding of the mantissas).

use std::ops::{Add, Div, Mul, Neg, Sub};

/// `m · 2^e` with 0.5 ≤ |m| < 1, or m = 0 (e = 0); m is NaN or infinite only after a division
/// by zero.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wide {
    m: f64,
    e: i64,
}

const TWO_POW_64: f64 = 18_446_744_073_709_551_616.0;

/// `x = m · 2^e` with 0.5 ≤ |m| < 1 (x finite and not 0); `(x, 0)` otherwise.
fn split(x: f64) -> (f64, i64) {
    if x == 0.0 || !x.is_finite() {
        return (x, 0);
    }
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i64;
    if biased == 0 {
        // Subnormal: scale into the normal range first.
        let (m, e) = split(x * TWO_POW_64);
        return (m, e - 64);
    }
    let m = f64::from_bits((bits & !(0x7ff << 52)) | (1022 << 52));
    (m, biased - 1022)
}

/// 2^e for |e| ≤ 1000, exactly.
fn pow2(e: i64) -> f64 {
    debug_assert!(e.abs() <= 1000);
    f64::from_bits(((e + 1023) as u64) << 52)
}

/// m · 2^e as the nearest `f64`: ±∞ above its range, 0 below.
fn scale(mut m: f64, mut e: i64) -> f64 {
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    if e > 2100 {
        return m * f64::INFINITY;
    }
    if e < -2200 {
        return m * 0.0;
    }
    while e > 1000 {
        m *= pow2(1000);
        e -= 1000;
    }
    while e < -1000 {
        m *= pow2(-1000);
        e += 1000;
    }
    m * pow2(e)
}

impl Wide {
    pub const ZERO: Wide = Wide { m: 0.0, e: 0 };

    fn normalized(m: f64, e: i64) -> Wide {
        let (m, d) = split(m);
        if m == 0.0 || !m.is_finite() {
            return Wide { m, e: 0 };
        }
        Wide { m, e: e + d }
    }

    /// The nearest `f64`: ±∞ beyond its range (which any limit then clamps correctly).
    pub fn to_f64(self) -> f64 {
        scale(self.m, self.e)
    }
}

impl From<f64> for Wide {
    fn from(x: f64) -> Wide {
        Wide::normalized(x, 0)
    }
}

impl Neg for Wide {
    type Output = Wide;
    fn neg(self) -> Wide {
        Wide { m: -self.m, e: self.e }
    }
}

impl Add for Wide {
    type Output = Wide;
    fn add(self, other: Wide) -> Wide {
        if self.m == 0.0 {
            return other;
        }
        if other.m == 0.0 {
            return self;
        }
        let (big, small) = if self.e >= other.e {
            (self, other)
        } else {
            (other, self)
        };
        Wide::normalized(big.m + scale(small.m, small.e - big.e), big.e)
    }
}

impl Sub for Wide {
    type Output = Wide;
    fn sub(self, other: Wide) -> Wide {
        self + -other
    }
}

impl Mul for Wide {
    type Output = Wide;
    fn mul(self, other: Wide) -> Wide {
        Wide::normalized(self.m * other.m, self.e + other.e)
    }
}

impl Div for Wide {
    type Output = Wide;
    fn div(self, other: Wide) -> Wide {
        Wide::normalized(self.m / other.m, self.e - other.e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn w(x: f64) -> Wide {
        Wide::from(x)
    }

    #[test]
    fn every_finite_f64_round_trips() {
        for x in [
            0.0,
            -0.0,
            1.0,
            -3.5,
            f64::MAX,
            -f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            -1.2e-310,
            std::f64::consts::PI,
        ] {
            assert_eq!(w(x).to_f64().to_bits(), x.to_bits(), "{x:e}");
        }
    }

    #[test]
    fn in_range_it_rounds_like_f64() {
        let (a, b, c) = (1.25e10, -3.75e-4, 7.0);
        assert_eq!((w(a) * w(b) + w(c)).to_f64(), a * b + c);
        assert_eq!((w(a) / w(b) - w(c)).to_f64(), a / b - c);
    }

    #[test]
    fn overflowing_intermediates_give_the_right_result() {
        // (MAX · 4 − MAX · 4) / 2 = 0, and (MAX · 4) / 8 = MAX / 2, where f64 gives NaN and ∞.
        let big = w(f64::MAX) * w(4.0);
        assert_eq!((big - big).to_f64(), 0.0);
        assert_eq!((big / w(8.0)).to_f64(), f64::MAX / 2.0);
        assert_eq!(big.to_f64(), f64::INFINITY);
        assert_eq!((-big).to_f64(), f64::NEG_INFINITY);
        // K α1 − K α2 with α1 = −α2 = 1.7e308: a number far beyond any limit, of the right sign.
        let d = w(14.0) * w(1.7e308) - w(14.0) * w(-1.7e308);
        assert_eq!(d.to_f64(), f64::INFINITY);
        let scaled = (d / w(1e300)).to_f64();
        assert!(
            (scaled / (14.0 * 3.4e8) - 1.0).abs() < 1e-15,
            "K (α1 − α2) / 1e300 = {scaled}"
        );
    }

    #[test]
    fn underflowing_intermediates_are_not_lost() {
        let tiny = w(1e-300) * w(1e-300);
        assert_eq!(tiny.to_f64(), 0.0);
        let one = (tiny * w(1e300) * w(1e300)).to_f64();
        assert!((one - 1.0).abs() < 1e-15, "1e-300 · 1e-300 · 1e300 · 1e300 = {one}");
    }
}
