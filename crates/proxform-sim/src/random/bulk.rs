//! Random numbers in bulk for the structure-of-arrays engine: a counter-based generator and a
//! branch-free normal transform over arrays.
//!
//! A draw is a pure function of its stream key (seed, run, UAV, source, step, as for
//! [`super::StepRng`]) and its counter: `mix(key + (c + 1)·φ)`, SplitMix64's output function
//! on the counter. Any draw can be computed alone, in any order, on any thread, so the engine
//! draws exactly the numbers it uses ("noise drawn only where it is observed") and the results
//! do not depend on the thread count. Normal deviates come from Box-Muller in f32 with
//! polynomial `ln`, `sin` and `cos` (no table, no branch, no rejection), written as loops over
//! arrays that the compiler vectorises. The f32 deviates have 24 random bits per uniform:
//! the largest deviate is about 5.8σ, enough for measurement noise.

use super::rng::{mix, source_key, step_part, RunKey, Source, GOLDEN};

/// The key of one UAV's stream `source` at step `step` in the run of `run`.
#[inline]
pub fn key(run: &RunKey, uav: u64, source: Source, step: u64) -> u64 {
    mix(source_key(run.uav(uav), source) ^ step_part(step))
}

/// Draw `c` of the stream of `key`: 64 random bits.
#[inline(always)]
pub fn bits(key: u64, c: u64) -> u64 {
    mix(key.wrapping_add(c.wrapping_add(1).wrapping_mul(GOLDEN)))
}

/// Draw `c` of the stream of `key` as a uniform number in [0, 1).
#[inline]
pub fn uniform(key: u64, c: u64) -> f64 {
    (bits(key, c) >> 11) as f64 / (1u64 << 53) as f64
}

const TWO_PI: f32 = std::f32::consts::TAU;
const LN_2: f32 = std::f32::consts::LN_2;

/// Natural logarithm of `x` in (0, 1], without a library call: `x = 2^e·m` with `m` in
/// [√½, √2), `ln m = 2·atanh(t)`, `t = (m − 1)/(m + 1)`, by its series to t⁹ (error < 1e-8).
#[inline(always)]
fn ln(x: f32) -> f32 {
    let b = x.to_bits();
    let mut e = ((b >> 23) & 0xff) as i32 - 127;
    let mut m = f32::from_bits((b & 0x007f_ffff) | 0x3f80_0000);
    let big = m > std::f32::consts::SQRT_2;
    m = if big { 0.5 * m } else { m };
    e += i32::from(big);
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    let s = 1.0 + t2 * (1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (1.0 / 7.0 + t2 * (1.0 / 9.0))));
    e as f32 * LN_2 + 2.0 * t * s
}

/// `(sin φ, cos φ)` for φ = 2π·x, x in [−½, ½): folded to [−π/2, π/2] and evaluated by Taylor
/// polynomials to the 11th and 12th power (error < 1e-7).
#[inline(always)]
fn sin_cos_turn(x: f32) -> (f32, f32) {
    let phi = TWO_PI * x;
    let half_pi = std::f32::consts::FRAC_PI_2;
    let far = phi.abs() > half_pi;
    let folded = if far { std::f32::consts::PI.copysign(phi) - phi } else { phi };
    let p2 = folded * folded;
    let s = folded
        * (1.0
            + p2 * (-1.0 / 6.0
                + p2 * (1.0 / 120.0 + p2 * (-1.0 / 5040.0 + p2 * (1.0 / 362_880.0 + p2 * (-1.0 / 39_916_800.0))))));
    let c = 1.0
        + p2 * (-0.5
            + p2 * (1.0 / 24.0
                + p2 * (-1.0 / 720.0
                    + p2 * (1.0 / 40_320.0 + p2 * (-1.0 / 3_628_800.0 + p2 * (1.0 / 479_001_600.0))))));
    (s, if far { -c } else { c })
}

/// Pairs of deviates transformed together: a lane count the compiler vectorises.
const LANES: usize = 8;

/// Fills `out` with standard normal deviates: draws `first/2 …` of the stream of `key`, two
/// deviates per draw (Box-Muller), `LANES` draws at a time, on the widest vector instructions
/// the processor has (AVX2 where present, chosen at run time by `pulp`): the same deviates on
/// every instruction set (IEEE arithmetic, nothing fused).
pub fn normals(key: u64, first: u64, out: &mut [f32]) {
    pulp::Arch::new().dispatch(Normals { key, first, out });
}

/// [`normals`] as an operation `pulp` compiles for each instruction set.
struct Normals<'a> {
    key: u64,
    first: u64,
    out: &'a mut [f32],
}

impl pulp::WithSimd for Normals<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        normals_in(self.key, self.first, self.out);
    }
}

/// [`normals`]' loops, inlined into each instruction set's version (the compiler vectorises
/// them for it).
#[inline(always)]
fn normals_in(key: u64, first: u64, out: &mut [f32]) {
    let pairs = out.len().div_ceil(2);
    let mut c = 0;
    while c < pairs {
        let mut u1 = [1.0f32; LANES];
        let mut x = [0.0f32; LANES];
        for l in 0..LANES {
            (u1[l], x[l]) = uniforms(bits(key, first + (c + l) as u64));
        }
        let mut z = [0.0f32; 2 * LANES];
        for l in 0..LANES {
            let r = (-2.0 * ln(u1[l])).sqrt();
            let (s, co) = sin_cos_turn(x[l]);
            z[2 * l] = r * co;
            z[2 * l + 1] = r * s;
        }
        let from = 2 * c;
        let to = out.len().min(from + 2 * LANES);
        out[from..to].copy_from_slice(&z[..to - from]);
        c += LANES;
    }
}

/// Box-Muller's two uniforms from 48 random bits: u1 in (0, 1], x in [−½, ½).
#[inline(always)]
fn uniforms(b: u64) -> (f32, f32) {
    const SCALE: f32 = 1.0 / (1u32 << 24) as f32;
    ((((b >> 40) as u32) + 1) as f32 * SCALE, ((b & 0x00ff_ffff) as u32) as f32 * SCALE - 0.5)
}

/// Two independent standard normal deviates from 48 random bits.
#[inline]
pub fn box_muller(b: u64) -> (f32, f32) {
    let (u1, x) = uniforms(b);
    let r = (-2.0 * ln(u1)).sqrt();
    let (s, c) = sin_cos_turn(x);
    (r * c, r * s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_polynomials_match_the_library() {
        for k in 1..=10_000 {
            let x = k as f32 / 10_000.0;
            assert!((ln(x) - x.ln()).abs() < 2e-6, "ln {x}: {} vs {}", ln(x), x.ln());
            let t = x - 0.5;
            let (s, c) = sin_cos_turn(t);
            let (s0, c0) = (TWO_PI * t).sin_cos();
            assert!((s - s0).abs() < 2e-6 && (c - c0).abs() < 2e-6, "{t}: {s} {c} vs {s0} {c0}");
        }
        assert_eq!(ln(1.0), 0.0);
    }

    #[test]
    fn deviates_are_standard_normal_and_reproducible() {
        let run = RunKey::new(7, 3);
        let k = key(&run, 11, Source::Sensing, 42);
        let n = 200_001;
        let mut z = vec![0.0f32; n];
        normals(k, 0, &mut z);
        let mean = z.iter().map(|&v| f64::from(v)).sum::<f64>() / n as f64;
        let var = z.iter().map(|&v| (f64::from(v) - mean).powi(2)).sum::<f64>() / n as f64;
        let kurt = z.iter().map(|&v| (f64::from(v) - mean).powi(4)).sum::<f64>() / n as f64 / (var * var);
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.01, "{var}");
        assert!((kurt - 3.0).abs() < 0.05, "{kurt}");
        // Tail mass beyond 2σ: 4.55 %.
        let tail = z.iter().filter(|v| v.abs() > 2.0).count() as f64 / n as f64;
        assert!((tail - 0.0455).abs() < 0.002, "{tail}");
        // The same counters give the same deviates, drawn alone or in bulk.
        let mut again = vec![0.0f32; 5];
        normals(k, 10, &mut again);
        assert_eq!(&again[..4], &z[20..24]);
        assert_eq!(again[4], box_muller(bits(k, 12)).0);
        // Another UAV, source or step is another stream.
        assert_ne!(key(&run, 12, Source::Sensing, 42), k);
        assert_ne!(key(&run, 11, Source::OwnState, 42), k);
        assert_ne!(key(&run, 11, Source::Sensing, 43), k);
        let u: f64 = (0..10_000).map(|c| uniform(k, c)).sum::<f64>() / 10_000.0;
        assert!((u - 0.5).abs() < 0.01, "{u}");
    }

    #[test]
    fn every_instruction_set_draws_the_same_deviates() {
        // `normals` runs on the widest vector instructions present (AVX2 on most x86-64);
        // `normals_in` called here is compiled for the baseline (SSE2 on x86-64). Bit for bit
        // equal, over lengths that leave partial lanes and over odd starting draws.
        let run = RunKey::new(3, 9);
        let arch = pulp::Arch::new();
        eprintln!("dispatching to {arch:?}");
        for (uav, len, first) in [(0, 1, 0), (1, 9, 3), (2, 17, 1), (3, 10_007, 11), (4, 4_096, 0)] {
            let k = key(&run, uav, Source::Sensing, 5);
            let (mut wide, mut base) = (vec![0.0f32; len], vec![0.0f32; len]);
            normals(k, first, &mut wide);
            normals_in(k, first, &mut base);
            let differ = wide.iter().zip(&base).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
            assert_eq!(differ, 0, "{differ} of {len} deviates differ");
        }
    }
}
