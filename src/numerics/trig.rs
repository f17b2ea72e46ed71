//! sin and cos of one argument together, with one argument reduction: the right-hand side of the
//! gear needs both for the drive angle α and the output angle β at every evaluation, and the two
//! `sin_cos` calls of the C library were about half its cost.
//!
//! The algorithm is FreeBSD's msun (derived from Sun's fdlibm), restricted to |x| < 2²⁰·π/2:
//! x = n·π/2 + (y₀ + y₁) by Cody–Waite reduction with π/2 split into 33-bit pieces
//! (`e_rem_pio2.c`, "medium" path, up to three rounds), then the minimax kernels on
//! [−π/4, π/4] (`k_sin.c`, `k_cos.c`, error below 1 ulp) chosen by n mod 4. Larger or non-finite
//! arguments fall back to [`f64::sin_cos`].

// the constants are fdlibm's, digit for digit (each rounds to the bit pattern the sources give)
#![allow(clippy::excessive_precision)]

/// 2/π.
const INV_PIO2: f64 = std::f64::consts::FRAC_2_PI;
/// First 33 bits of π/2.
const PIO2_1: f64 = 1.570_796_326_734_125_614_17e0;
/// π/2 − PIO2_1.
const PIO2_1T: f64 = 6.077_100_506_506_192_249_32e-11;
/// Second 33 bits of π/2.
const PIO2_2: f64 = 6.077_100_506_303_965_976_60e-11;
/// π/2 − (PIO2_1 + PIO2_2).
const PIO2_2T: f64 = 2.022_266_248_795_950_631_54e-21;
/// Third 33 bits of π/2.
const PIO2_3: f64 = 2.022_266_248_711_166_455_80e-21;
/// π/2 − (PIO2_1 + PIO2_2 + PIO2_3).
const PIO2_3T: f64 = 8.478_427_660_368_899_569_97e-32;
/// Arguments up to this size use the reduction above (n < 2²⁰ keeps n·PIO2_1 exact).
const MEDIUM: f64 = 1_647_099.0;

/// 1.5·2⁵²: adding and subtracting it rounds |v| < 2⁵¹ to the nearest integer.
const TO_INT: f64 = 6_755_399_441_055_744.0;

/// Biased exponent of x.
#[inline(always)]
fn exponent(x: f64) -> i64 {
    ((x.to_bits() >> 52) & 0x7ff) as i64
}

/// x = n·π/2 + y₀ + y₁ with |y₀ + y₁| ≤ π/4 (approximately), |y₁| ≤ ulp(y₀)/2: returns (n, y₀, y₁).
#[inline(always)]
fn reduce(x: f64) -> (i64, f64, f64) {
    // round to nearest by adding and subtracting 1.5·2⁵² (fdlibm's rnint; no libm call)
    let f = (x * INV_PIO2 + TO_INT) - TO_INT;
    let n = f as i64;
    let mut r = x - f * PIO2_1;
    let mut w = f * PIO2_1T; // first round: good to 85 bits
    let j = exponent(x);
    let mut y0 = r - w;
    if j - exponent(y0) > 16 {
        // second round: good to 118 bits
        let t = r;
        w = f * PIO2_2;
        r = t - w;
        w = f * PIO2_2T - ((t - r) - w);
        y0 = r - w;
        if j - exponent(y0) > 49 {
            // third round: 151 bits, covers all cases
            let t = r;
            w = f * PIO2_3;
            r = t - w;
            w = f * PIO2_3T - ((t - r) - w);
            y0 = r - w;
        }
    }
    let y1 = (r - y0) - w;
    (n, y0, y1)
}

/// sin(x + y) on [−π/4, π/4], y a tail below ulp(x)/2 (fdlibm `__kernel_sin` with iy = 1).
#[inline(always)]
fn kernel_sin(x: f64, y: f64) -> f64 {
    const S1: f64 = -1.666_666_666_666_663_243_48e-1;
    const S2: f64 = 8.333_333_333_322_489_461_24e-3;
    const S3: f64 = -1.984_126_982_985_794_931_34e-4;
    const S4: f64 = 2.755_731_370_707_006_767_89e-6;
    const S5: f64 = -2.505_076_025_340_686_341_95e-8;
    const S6: f64 = 1.589_690_995_211_550_102_21e-10;
    let z = x * x;
    let w = z * z;
    let r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let v = z * x;
    x - ((z * (0.5 * y - v * r) - y) - v * S1)
}

/// cos(x + y) on [−π/4, π/4] (FreeBSD `__kernel_cos`).
#[inline(always)]
fn kernel_cos(x: f64, y: f64) -> f64 {
    const C1: f64 = 4.166_666_666_666_660_190_37e-2;
    const C2: f64 = -1.388_888_888_887_410_957_49e-3;
    const C3: f64 = 2.480_158_728_947_672_941_78e-5;
    const C4: f64 = -2.755_731_435_139_066_330_35e-7;
    const C5: f64 = 2.087_572_321_298_174_827_90e-9;
    const C6: f64 = -1.135_964_755_778_819_482_65e-11;
    let z = x * x;
    let w = z * z;
    let r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    w + (((1.0 - w) - hz) + (z * r - x * y))
}

/// (sin x, cos x), within 1 ulp of the exact values (the C library's `sin_cos` for |x| ≥ 1.6·10⁶
/// and non-finite x).
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if x.is_nan() || x.abs() >= MEDIUM {
        return x.sin_cos();
    }
    let (n, y0, y1) = reduce(x);
    let s = kernel_sin(y0, y1);
    let c = kernel_cos(y0, y1);
    match n & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the C library's sin and cos on arguments spread over the whole reduced range (a
    /// fixed pseudo-random sequence), next to multiples of π/2 (where the reduction cancels), tiny
    /// and fallback arguments: both are within 1 ulp of the exact value, so within 2 ulp of each
    /// other.
    #[test]
    fn matches_the_c_library() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut args: Vec<f64> = Vec::new();
        for scale in [1e-8, 1e-3, 1.0, 4.0, 30.0, 1e3, 1e5, 1.6e6] {
            for _ in 0..20_000 {
                args.push((2.0 * next() - 1.0) * scale);
            }
        }
        for k in -2000..2000 {
            let m = k as f64 * std::f64::consts::FRAC_PI_2;
            args.extend([m, m.next_up(), m.next_down(), m * 733.0]);
        }
        args.extend([0.0, -0.0, 1e-300, 5e-324, 2e6, -1e10, 1e300]);
        let mut worst = 0.0_f64;
        for &x in &args {
            let (s, c) = sin_cos(x);
            for (v, r) in [(s, x.sin()), (c, x.cos())] {
                let ulp = r.abs().next_up() - r.abs();
                let err = (v - r).abs() / ulp;
                worst = worst.max(err);
                assert!(err <= 2.0, "x = {x:e}: {v:e} vs {r:e} ({err} ulp)");
            }
        }
        assert!(sin_cos(f64::NAN).0.is_nan() && sin_cos(f64::INFINITY).1.is_nan());
        eprintln!("largest difference: {worst:.2} ulp");
    }
}
