//! Q31.32 fixed-point arithmetic for the on-device models: every operation
//! saturates instead of wrapping, and transcendental functions are computed
//! in integers (Taylor series for sine, bit-by-bit logarithm, a table of
//! `2^(2^-i)` for the exponential) to about 1e-9, so that a lobe `c^n` with
//! n = 10⁴ keeps a relative error near 1e-5. Floats appear only in
//! [`Fx::from_f32`] / [`Fx::to_f32`], at the edge.

/// A Q31.32 number: range ±2.1·10⁹, resolution 2.3·10⁻¹⁰.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub struct Fx(pub i64);

const FRAC: u32 = 32;
const Q62: u32 = 62;

/// `2^(2^-i) · 2^62` for i = 1..=32.
const EXP2_TABLE: [u64; 32] = [
    0x5a827999fcef3242,
    0x4c1bf828c6dc54b8,
    0x45cae0f1f545eb73,
    0x42d561b3e6243d8a,
    0x4166c34c5615d0ec,
    0x40b268f9de0183ba,
    0x4058f6a7ecccd5b6,
    0x402c6be96af2fb58,
    0x4016321b687027a8,
    0x400b18178ba33b14,
    0x40058bce410147e8,
    0x4002c5d7bff71daf,
    0x400162e807ee7e5b,
    0x4000b1730df6a524,
    0x400058b9497b8152,
    0x40002c5c955dd701,
    0x4000162e46d6f26c,
    0x40000b1722757b1b,
    0x4000058b90fd3e0c,
    0x400002c5c86f3f26,
    0x40000162e433c79b,
    0x400000b17218edd0,
    0x40000058b90c3968,
    0x4000002c5c860d54,
    0x400000162e4302d2,
    0x4000000b17218073,
    0x400000058b90bffc,
    0x40000002c5c85fef,
    0x4000000162e42ff3,
    0x40000000b17217f9,
    0x4000000058b90bfc,
    0x400000002c5c85fe,
];

impl Fx {
    pub const ZERO: Fx = Fx(0);
    pub const ONE: Fx = Fx(1 << FRAC);
    pub const MAX: Fx = Fx(i64::MAX);
    pub const PI: Fx = Fx(13_493_037_705);
    pub const TWO_PI: Fx = Fx(26_986_075_409);
    pub const HALF_PI: Fx = Fx(6_746_518_852);
    pub const INV_PI: Fx = Fx(1_367_130_551);
    pub const INV_TWO_PI: Fx = Fx(683_565_276);
    pub const LOG2_E: Fx = Fx(6_196_328_018);

    pub const fn from_int(i: i32) -> Fx {
        Fx((i as i64) << FRAC)
    }

    /// The edge from floats: `None` for NaN, infinities and values out of range.
    pub fn from_f32(x: f32) -> Option<Fx> {
        let v = x as f64 * (1u64 << FRAC) as f64;
        (x.is_finite() && v.abs() < i64::MAX as f64).then(|| Fx(libm::round(v) as i64))
    }

    /// The edge to floats.
    pub fn to_f32(self) -> f32 {
        (self.0 as f64 / (1u64 << FRAC) as f64) as f32
    }

    fn sat(v: i128) -> Fx {
        Fx(v.clamp(i64::MIN as i128, i64::MAX as i128) as i64)
    }

    pub fn plus(self, o: Fx) -> Fx {
        Fx(self.0.saturating_add(o.0))
    }

    pub fn minus(self, o: Fx) -> Fx {
        Fx(self.0.saturating_sub(o.0))
    }

    pub fn negated(self) -> Fx {
        Fx(self.0.saturating_neg())
    }

    pub fn times(self, o: Fx) -> Fx {
        Self::sat((self.0 as i128 * o.0 as i128) >> FRAC)
    }

    /// Division; by zero it saturates to the sign of the dividend (0/0 = 0).
    pub fn over(self, o: Fx) -> Fx {
        if o.0 == 0 {
            return Fx(match self.0.signum() {
                1 => i64::MAX,
                -1 => i64::MIN,
                _ => 0,
            });
        }
        Self::sat(((self.0 as i128) << FRAC) / o.0 as i128)
    }

    pub fn max(self, o: Fx) -> Fx {
        if self.0 >= o.0 {
            self
        } else {
            o
        }
    }

    pub fn clamp(self, lo: Fx, hi: Fx) -> Fx {
        Fx(self.0.clamp(lo.0, hi.0))
    }

    /// Square root of a non-negative value (negative values give zero).
    pub fn sqrt(self) -> Fx {
        if self.0 <= 0 {
            return Fx::ZERO;
        }
        Fx(isqrt((self.0 as u128) << FRAC) as i64)
    }

    /// Sine and cosine of an angle in radians.
    pub fn sin_cos(self) -> (Fx, Fx) {
        // Reduce to (−π, π], then to [0, π/2] by symmetry.
        let two_pi = Fx::TWO_PI.0 as i128;
        let mut x = (self.0 as i128) % two_pi;
        if x > Fx::PI.0 as i128 {
            x -= two_pi;
        } else if x <= -(Fx::PI.0 as i128) {
            x += two_pi;
        }
        let neg = x < 0;
        let a = x.unsigned_abs() as i64; // [0, π]
                                         // sin(a) = sin(π − a), cos(a) = −cos(π − a) in the second quadrant.
        let (c_sign, r) = if a > Fx::HALF_PI.0 { (-1, Fx::PI.0 - a) } else { (1, a) };
        let sin = sin_quadrant(r);
        let cos = sin_quadrant(Fx::HALF_PI.0 - r) * c_sign;
        (Fx(if neg { -sin } else { sin }), Fx(cos))
    }

    /// Base-2 logarithm of a positive value (non-positive values saturate low).
    pub fn log2(self) -> Fx {
        if self.0 <= 0 {
            return Fx(i64::MIN);
        }
        let msb = 63 - self.0.leading_zeros() as i64; // value = m · 2^(msb − 32)
        let e = msb - FRAC as i64;
        let mut m: u128 = if msb <= Q62 as i64 {
            (self.0 as u128) << (Q62 as i64 - msb)
        } else {
            (self.0 as u128) >> (msb - Q62 as i64)
        };
        let mut frac: i64 = 0;
        for bit in (0..FRAC).rev() {
            m = (m * m) >> Q62;
            if m >= 2u128 << Q62 {
                m >>= 1;
                frac |= 1 << bit;
            }
        }
        Fx((e << FRAC) + frac)
    }

    /// `2^self`, saturating above the range and flushing to zero below it.
    pub fn exp2(self) -> Fx {
        let k = self.0 >> FRAC; // floor
        let f = (self.0 & ((1 << FRAC) - 1)) as u64;
        if k >= 31 {
            return Fx::MAX;
        }
        if k < -64 {
            return Fx::ZERO;
        }
        let mut r: u128 = 1 << Q62;
        for (i, c) in EXP2_TABLE.iter().enumerate() {
            if f & (1 << (FRAC as usize - 1 - i)) != 0 {
                r = (r * *c as u128) >> Q62;
            }
        }
        // r is 2^f in Q62; to Q32 and scale by 2^k.
        let shift = Q62 as i64 - FRAC as i64 - k;
        Fx(if shift >= 128 { 0 } else { (r >> shift) as i64 })
    }

    /// `e^self`.
    pub fn exp(self) -> Fx {
        self.times(Fx::LOG2_E).exp2()
    }

    /// `self^p` for a positive base; zero for a non-positive base.
    pub fn powf(self, p: Fx) -> Fx {
        if self.0 <= 0 {
            return Fx::ZERO;
        }
        p.times(self.log2()).exp2()
    }

    /// `self^n` for a small non-negative integer `n`.
    pub fn powi(self, n: u32) -> Fx {
        (0..n).fold(Fx::ONE, |acc, _| acc.times(self))
    }
}

/// `1/(2k·(2k+1))` in Q62 for k = 1..=7: the Taylor series' divisions as
/// multiplications (a 128-bit division is a software routine of hundreds of
/// instructions on the Cortex-M4; measured by `chip-bench`, the geometry's
/// three sines and cosines cost 145 000 instructions with it).
const SIN_RECIPROCALS: [i128; 8] = {
    let mut r = [0i128; 8];
    let mut k = 1;
    while k <= 7 {
        let d = (2 * k * (2 * k + 1)) as i128;
        // Rounded to nearest.
        r[k] = ((1i128 << Q62) + d / 2) / d;
        k += 1;
    }
    r
};

/// `sin(r) · 2^32` for r ∈ [0, π/2] in Q32, by its Taylor series to x¹⁵ in Q62
/// (truncation below 10⁻¹¹).
fn sin_quadrant(r: i64) -> i64 {
    let x = (r as i128) << (Q62 - FRAC);
    let x2 = (x * x) >> Q62;
    let one: i128 = 1 << Q62;
    // 1 − x²/(2·3)(1 − x²/(4·5)(1 − …(1 − x²/(14·15))))
    let mut acc = one;
    for k in (1..=7).rev() {
        acc = one - ((((x2 * acc) >> Q62) * SIN_RECIPROCALS[k]) >> Q62);
    }
    (((x * acc) >> Q62) >> (Q62 - FRAC)) as i64
}

/// Integer square root (floor).
fn isqrt(n: u128) -> u128 {
    if n == 0 {
        return 0;
    }
    let mut x = 1u128 << (128 - n.leading_zeros()).div_ceil(2);
    loop {
        let y = (x + n / x) / 2;
        if y >= x {
            return x;
        }
        x = y;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(x: f64) -> Fx {
        Fx::from_f32(x as f32).unwrap()
    }

    fn v(x: Fx) -> f64 {
        x.0 as f64 / 4294967296.0
    }

    #[test]
    fn transcendental_functions_reach_1e_9() {
        for i in -700..=700 {
            let a = i as f64 * 0.01;
            let (s, c) = Fx(libm::round(a * 4294967296.0) as i64).sin_cos();
            assert!((v(s) - a.sin()).abs() < 2e-9 && (v(c) - a.cos()).abs() < 2e-9, "{a}");
        }
        for x in [1e-6, 0.001, 0.37, 0.5, 0.999_999, 1.0, 1.5, 2.0, 3.0, 1000.0, 2e5] {
            let fx = Fx(libm::round(x * 4294967296.0) as i64);
            assert!((v(fx.log2()) - libm::log2(v(fx))).abs() < 3e-9, "log2 {x}");
        }
        for y in [-40.0, -10.5, -1.0, -0.25, 0.0, 0.3, 1.0, 7.9, 20.0] {
            let got = v(f(y).exp2());
            let want = libm::exp2(v(f(y)));
            assert!((got - want).abs() <= 1e-9 * want.max(1.0) + 3e-10, "exp2 {y}: {got} vs {want}");
        }
        assert!((v(f(2.0).sqrt()) - 2f64.sqrt()).abs() < 1e-9);
        assert!((v(f(1e-6).sqrt()) - v(f(1e-6)).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn sharp_lobes_keep_their_relative_accuracy() {
        for c in [0.9999, 0.9995, 0.999, 0.99] {
            let got = v(f(c).powf(f(1.0e4)));
            let want = libm::pow(Fx::from_f32(c as f32).map(v).unwrap(), 1.0e4);
            assert!((got - want).abs() <= 1e-4 * want + 1e-9, "{c}: {got} vs {want}");
        }
    }

    #[test]
    fn nothing_wraps() {
        assert_eq!(Fx::MAX.times(Fx::MAX), Fx::MAX);
        assert_eq!(Fx::MAX.plus(Fx::ONE), Fx::MAX);
        assert_eq!(Fx::ONE.over(Fx::ZERO), Fx::MAX);
        assert_eq!(f(40.0).exp2(), Fx::MAX);
        assert_eq!(f(-100.0).exp2(), Fx::ZERO);
        assert_eq!(Fx::ZERO.powf(f(2.0)), Fx::ZERO);
        assert!(Fx::from_f32(f32::NAN).is_none() && Fx::from_f32(1e30).is_none());
    }
}
