//! Seeded random streams.
//!
//! Every random draw belongs to a stream named by (seed, run index, UAV, noise source) and is
//! taken from a generator keyed by that stream and the step number. No generator state is
//! carried between steps or shared between UAVs, so a run's numbers do not depend on the
//! order in which UAVs are stepped or on the number of threads. The generator is SplitMix64
//! (Steele, Lea & Flood 2014), whose output function is a strong 64-bit mixer.

use std::convert::Infallible;

use rand::TryRng;

/// The noise sources of a UAV.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u64)]
pub enum Source {
    /// Noise on the UAV's estimate of its own state.
    OwnState = 1,
    /// Noise on its observations of others.
    Sensing = 2,
    /// Error on the inputs it applies.
    Actuation = 3,
    /// Losses on its radio channel.
    Radio = 4,
    /// Its turbulence field.
    Wind = 5,
    /// The slowly varying bias of its own position fix.
    Gnss = 6,
}

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

#[inline]
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The key of one stream.
#[inline]
pub fn stream_key(seed: u64, run: u64, uav: u64, source: Source) -> u64 {
    let mut k = mix(seed ^ GOLDEN);
    k = mix(k ^ run.wrapping_mul(GOLDEN));
    k = mix(k ^ uav.wrapping_mul(0xD1B5_4A32_D192_ED03));
    mix(k ^ (source as u64).wrapping_mul(0x8CB9_2BA7_2F3D_8DD7))
}

/// SplitMix64 generator for one stream at one step.
#[derive(Debug, Clone)]
pub struct StepRng {
    state: u64,
}

impl StepRng {
    /// The generator of stream `key` at step `step`.
    #[inline]
    pub fn new(key: u64, step: u64) -> Self {
        Self { state: mix(key ^ mix(step.wrapping_add(GOLDEN))) }
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.next()
    }

    #[inline]
    fn next(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN);
        mix(self.state)
    }
}

impl TryRng for StepRng {
    type Error = Infallible;

    #[inline]
    fn try_next_u32(&mut self) -> Result<u32, Infallible> {
        Ok((self.next() >> 32) as u32)
    }

    #[inline]
    fn try_next_u64(&mut self) -> Result<u64, Infallible> {
        Ok(self.next())
    }

    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
        for chunk in dst.chunks_mut(8) {
            let v = self.next().to_le_bytes();
            chunk.copy_from_slice(&v[..chunk.len()]);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngExt;
    use rand_distr::StandardNormal;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a = stream_key(7, 0, 1, Source::Sensing);
        assert_eq!(a, stream_key(7, 0, 1, Source::Sensing));
        assert_ne!(a, stream_key(7, 0, 2, Source::Sensing));
        assert_ne!(a, stream_key(7, 1, 1, Source::Sensing));
        assert_ne!(a, stream_key(7, 0, 1, Source::OwnState));
        let x: f64 = StepRng::new(a, 3).sample(StandardNormal);
        let y: f64 = StepRng::new(a, 3).sample(StandardNormal);
        let z: f64 = StepRng::new(a, 4).sample(StandardNormal);
        assert_eq!(x.to_bits(), y.to_bits());
        assert_ne!(x.to_bits(), z.to_bits());
    }

    #[test]
    fn normal_draws_have_unit_variance() {
        let key = stream_key(1, 0, 0, Source::Sensing);
        let n = 200_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for step in 0..n {
            let v: f64 = StepRng::new(key, step).sample(StandardNormal);
            s += v;
            s2 += v * v;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!((var - 1.0).abs() < 0.02, "var {var}");
    }
}
