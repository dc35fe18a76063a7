//! Deterministic transcendental functions.
//!
//! The page (wasm) and the CLI (native) must write byte-identical G-code for the same part and
//! options. `+ − × ÷` and `sqrt` are exact IEEE operations on every target, but the `f64` methods
//! `exp`, `ln`, `sin`, … call the platform's libm natively (glibc) and a Rust port of musl's in
//! wasm, which may differ in the last bit. Every stage calls these wrappers instead: one pure-Rust
//! implementation (the `libm` crate) on every target.

#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}
/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}
#[inline]
pub fn tan(x: f64) -> f64 {
    libm::tan(x)
}
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}
#[inline]
pub fn acos(x: f64) -> f64 {
    libm::acos(x)
}
#[inline]
pub fn asin(x: f64) -> f64 {
    libm::asin(x)
}
#[inline]
pub fn powf(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}
#[inline]
pub fn hypot(x: f64, y: f64) -> f64 {
    libm::hypot(x, y)
}
/// `atan2(v.y, v.x)`: the argument of a complex number stored as a `DVec2`.
#[inline]
pub fn arg(v: glam::DVec2) -> f64 {
    libm::atan2(v.y, v.x)
}

/// `a.min(b)` (NaN ignored as there) by comparisons. In wasm `f64::min` is a call to `fmin`
/// (wasm's own `f64.min` propagates NaN, so LLVM cannot use it); the hot loops use this instead
/// (2–5 % of the spacing's and the verifier's time in wasm went into those calls). The same value
/// as `f64::min` but for the sign of a zero when both are zeros, which `f64::min` leaves to the
/// platform.
#[inline]
pub fn min(a: f64, b: f64) -> f64 {
    if b < a || a.is_nan() {
        b
    } else {
        a
    }
}

/// `a.max(b)` by comparisons, as [`min`].
#[inline]
pub fn max(a: f64, b: f64) -> f64 {
    if b > a || a.is_nan() {
        b
    } else {
        a
    }
}

/// `x.rem_euclid(TAU)`, bit for bit, without the `fmod` call (a libm routine, 2–3 % of the
/// spacing's time) where `x` lies in (−2π, 4π), as the angles wrapped here do: there `x % 2π` is
/// `x` or the exact `x − 2π` (Sterbenz), and a negative remainder gets the same rounded `+ 2π`.
#[inline]
pub fn rem_tau(x: f64) -> f64 {
    use std::f64::consts::TAU;
    if (0.0..TAU).contains(&x) {
        x
    } else if (TAU..2.0 * TAU).contains(&x) {
        x - TAU
    } else if x > -TAU && x < 0.0 {
        x + TAU
    } else {
        x.rem_euclid(TAU)
    }
}

/// An angle (or an angle difference) wrapped into (−π, π].
pub fn wrap_pi(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let r = rem_tau(a + PI) - PI;
    if r <= -PI {
        r + TAU
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_std_to_an_ulp_or_two() {
        for k in 0..1000 {
            let x = -20.0 + 40.0 * k as f64 / 999.0;
            let close = |a: f64, b: f64| (a - b).abs() <= 4.0 * f64::EPSILON * a.abs().max(b.abs()).max(1e-300);
            assert!(close(exp(x), x.exp()), "exp({x})");
            assert!(close(sin(x), x.sin()) || (sin(x) - x.sin()).abs() < 1e-15, "sin({x})");
            assert!(close(cos(x), x.cos()) || (cos(x) - x.cos()).abs() < 1e-15, "cos({x})");
            assert!(close(atan2(x, 1.5), x.atan2(1.5)), "atan2({x})");
            if x > 0.0 {
                assert!(close(ln(x), x.ln()) || (ln(x) - x.ln()).abs() < 1e-15, "ln({x})");
            }
        }
    }

    #[test]
    fn min_and_max_are_std_s_but_for_the_sign_of_zero() {
        let xs = [f64::NAN, f64::NEG_INFINITY, -2.5, -0.0, 0.0, 1e-300, 3.0, f64::INFINITY];
        for a in xs {
            for b in xs {
                let same =
                    |x: f64, y: f64| x.to_bits() == y.to_bits() || (x == 0.0 && y == 0.0) || (x.is_nan() && y.is_nan());
                assert!(same(min(a, b), a.min(b)), "min({a}, {b})");
                assert!(same(max(a, b), a.max(b)), "max({a}, {b})");
            }
        }
    }

    #[test]
    fn rem_tau_is_rem_euclid_bit_for_bit() {
        use std::f64::consts::TAU;
        let mut xs = vec![0.0, -0.0, TAU, -TAU, 2.0 * TAU, -2.0 * TAU, 4.0 * TAU, 1e-300, -1e-300, -1e-17, 1e300];
        // Each limit's neighbours, one ulp either side.
        for x in [TAU, 2.0 * TAU, -TAU] {
            xs.extend([f64::from_bits(x.to_bits() + 1), f64::from_bits(x.to_bits() - 1)]);
        }
        let mut rng = crate::fixtures::SplitMix64::skipped(7, 0);
        xs.extend((0..100_000).map(|_| 40.0 * rng.unit() - 20.0));
        for x in xs {
            assert_eq!(rem_tau(x).to_bits(), x.rem_euclid(TAU).to_bits(), "{x:e}");
        }
        assert!(rem_tau(f64::NAN).is_nan());
    }
}
