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
    /// Where it starts, when the scenario scatters the formation.
    Placement = 7,
}

pub(crate) const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

#[inline(always)]
pub(crate) fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The key of one stream.
#[inline]
pub fn stream_key(seed: u64, run: u64, uav: u64, source: Source) -> u64 {
    source_key(uav_key(run_key(seed, run), uav), source)
}

/// The (seed, run) part of every stream key of a run: the first half of [`stream_key`],
/// computed once per run.
#[inline]
pub fn run_key(seed: u64, run: u64) -> u64 {
    mix(mix(seed ^ GOLDEN) ^ run.wrapping_mul(GOLDEN))
}

/// The part of the keys of UAV `uav`'s streams in the run of `run_key`.
#[inline]
pub fn uav_key(run_key: u64, uav: u64) -> u64 {
    mix(run_key ^ uav.wrapping_mul(0xD1B5_4A32_D192_ED03))
}

/// The key of stream `source` of the UAV of `uav_key`: equal to [`stream_key`].
#[inline]
pub fn source_key(uav_key: u64, source: Source) -> u64 {
    mix(uav_key ^ (source as u64).wrapping_mul(0x8CB9_2BA7_2F3D_8DD7))
}

/// The step's part of every generator of step `step`.
#[inline]
pub fn step_part(step: u64) -> u64 {
    mix(step.wrapping_add(GOLDEN))
}

/// The (seed, run) that every stream of one run belongs to, with its part of the keys mixed
/// once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunKey {
    /// Base seed.
    pub seed: u64,
    /// Run index within the batch.
    pub run: u64,
    mixed: u64,
}

impl RunKey {
    /// The key of run `run` of seed `seed`.
    pub fn new(seed: u64, run: u64) -> Self {
        Self { seed, run, mixed: run_key(seed, run) }
    }

    /// The part of UAV `uav`'s stream keys (pass it to [`StreamKey::rng_of`]).
    #[inline]
    pub fn uav(&self, uav: u64) -> u64 {
        uav_key(self.mixed, uav)
    }

    /// This run's streams at step `step`.
    #[inline]
    pub fn at(&self, step: u64) -> StreamKey {
        StreamKey { run: *self, step, step_part: step_part(step) }
    }
}

/// Every stream of one run at one step: the value each random draw of a step is keyed by
/// (seed, run, step), with the run's and the step's parts mixed once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamKey {
    run: RunKey,
    step: u64,
    step_part: u64,
}

impl StreamKey {
    /// The run.
    pub fn run(&self) -> &RunKey {
        &self.run
    }

    /// The step.
    pub fn step(&self) -> u64 {
        self.step
    }

    /// The generator of UAV `uav`'s stream `source` at this step: the same as
    /// `StepRng::new(stream_key(seed, run, uav, source), step)`.
    #[inline]
    pub fn rng(&self, uav: u64, source: Source) -> StepRng {
        self.rng_of(self.run.uav(uav), source)
    }

    /// The same from the UAV's part of the key ([`RunKey::uav`]), computed once per UAV.
    #[inline]
    pub fn rng_of(&self, uav_key: u64, source: Source) -> StepRng {
        StepRng::at(source_key(uav_key, source), self.step_part)
    }
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
        Self::at(key, step_part(step))
    }

    /// The generator of stream `key` at the step whose [`step_part`] is `part` (computed once
    /// per step for every stream).
    #[inline]
    pub fn at(key: u64, part: u64) -> Self {
        Self { state: mix(key ^ part) }
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
    fn precomputed_key_parts_give_the_same_streams() {
        for (seed, run, uav, step) in [(1u64, 0u64, 0u64, 0u64), (7, 3, 123_456, 99), (u64::MAX, u64::MAX, 5, 1 << 62)]
        {
            for source in [Source::OwnState, Source::Sensing, Source::Radio] {
                let key = source_key(uav_key(run_key(seed, run), uav), source);
                assert_eq!(key, stream_key(seed, run, uav, source));
                let (mut a, mut b) = (StepRng::new(key, step), StepRng::at(key, step_part(step)));
                assert_eq!(a.next_u64(), b.next_u64());
            }
        }
    }

    #[test]
    fn a_stream_key_gives_the_streams_of_its_seed_run_and_step() {
        let k = RunKey::new(7, 3).at(99);
        for (uav, source) in [(0, Source::OwnState), (123_456, Source::Actuation), (5, Source::Wind)] {
            let mut a = k.rng(uav, source);
            let mut b = StepRng::new(stream_key(7, 3, uav, source), 99);
            assert_eq!(a.next_u64(), b.next_u64());
        }
        assert_ne!(RunKey::new(7, 3).at(100).rng(0, Source::Radio).next_u64(), k.rng(0, Source::Radio).next_u64());
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
