//! Recording a run's trajectories in memory, one row per UAV per step.

use proxform_core::state::State9;

use proxform_scenario::Scenario;

use super::observer::{formation_error_to, Observer, StepFrame};

/// One UAV at one step.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryRow {
    /// Time (s).
    pub t: f64,
    /// UAV index.
    pub uav: u32,
    /// True state (SI, rad).
    pub state: State9,
    /// Formation error x, y, z (m), α, β, γ (rad); zero for the navigator.
    pub error: [f64; 6],
    /// The decision's outcome at the previous update: "held", "adjusted", "alone", or
    /// "navigator"/"leads" (the navigator's successor)/"initial".
    pub outcome: &'static str,
    /// True when the UAV's course was inside its envelope (it held).
    pub in_envelope: bool,
    /// True when every formation error is within the allowable error.
    pub within_allowable: bool,
}

/// UAVs recorded by default: all of a small formation, the first ones of a large swarm.
pub const DEFAULT_SAMPLE: usize = 64;
/// Most steps streamed to the sink: a longer flight is streamed every n-th step.
pub const MAX_STREAMED_STEPS: u64 = 1_000_000;
/// Most steps kept in memory (for figures): a longer flight keeps every n-th step.
pub const MAX_KEPT_STEPS: u64 = 5_000;

/// Where the rows of a run go as it flies (a file, in the binary): the simulator writes none.
pub trait RowSink: Send {
    /// One row.
    fn row(&mut self, row: &TrajectoryRow);
    /// After the last row: flush, and report the first error met (as text).
    fn finish(&mut self) -> Result<(), String> {
        Ok(())
    }
}

/// Observer recording the rows of a run for the first `sample` UAVs, or for the chosen ones:
/// every `stream_every`-th step to its sink as the flight goes, and every `keep_every`-th step
/// in memory, so memory stays bounded whatever the duration (and, for more than
/// [`DEFAULT_SAMPLE`] UAVs, whatever their number: the steps are decimated in proportion).
pub struct Trajectory {
    /// Rows kept in memory, in time order, then UAV order.
    pub rows: Vec<TrajectoryRow>,
    /// Number of UAVs recorded (the first ones), when none are chosen.
    pub sample: usize,
    /// The UAVs recorded (indices, ascending), when chosen.
    pub uavs: Option<Vec<usize>>,
    /// Steps between rows kept in memory.
    pub keep_every: u64,
    /// Steps between rows streamed to the sink.
    pub stream_every: u64,
    sink: Option<Box<dyn RowSink>>,
}

impl std::fmt::Debug for Trajectory {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Trajectory")
            .field("rows", &self.rows.len())
            .field("sample", &self.sample)
            .field("keep_every", &self.keep_every)
            .field("stream_every", &self.stream_every)
            .field("sink", &self.sink.is_some())
            .finish()
    }
}

impl Default for Trajectory {
    fn default() -> Self {
        Self { rows: Vec::new(), sample: DEFAULT_SAMPLE, uavs: None, keep_every: 1, stream_every: 1, sink: None }
    }
}

impl Trajectory {
    /// A recording of a flight of `steps` steps: every step kept up to [`MAX_KEPT_STEPS`],
    /// evenly decimated beyond; streamed to `sink` (if any) every step up to
    /// [`MAX_STREAMED_STEPS`], evenly decimated beyond.
    pub fn for_flight(steps: u64, sink: Option<Box<dyn RowSink>>) -> Self {
        Self {
            keep_every: steps.div_ceil(MAX_KEPT_STEPS).max(1),
            stream_every: steps.div_ceil(MAX_STREAMED_STEPS).max(1),
            sink,
            ..Self::default()
        }
    }

    /// The same recording of the UAVs `uavs` (indices) instead of the first ones: more than
    /// [`DEFAULT_SAMPLE`] of them thin the steps kept and streamed in proportion, so that the
    /// rows stay within the same bounds ([`MAX_KEPT_STEPS`] and [`MAX_STREAMED_STEPS`] times
    /// [`DEFAULT_SAMPLE`]).
    pub fn of_uavs(self, steps: u64, mut uavs: Vec<usize>) -> Self {
        uavs.sort_unstable();
        uavs.dedup();
        let scale = (uavs.len() as u64).div_ceil(DEFAULT_SAMPLE as u64).max(1);
        let every = |most: u64| steps.saturating_mul(scale).div_ceil(most).max(1);
        Self { keep_every: every(MAX_KEPT_STEPS), stream_every: every(MAX_STREAMED_STEPS), uavs: Some(uavs), ..self }
    }

    /// Takes the sink back (to finish writing).
    pub fn take_sink(&mut self) -> Option<Box<dyn RowSink>> {
        self.sink.take()
    }
}

impl Observer for Trajectory {
    fn on_step(&mut self, scenario: &Scenario, frame: &StepFrame<'_>) {
        let keep = frame.k % self.keep_every == 0;
        let stream = self.sink.is_some() && frame.k % self.stream_every == 0;
        if !keep && !stream {
            return;
        }
        let nav = scenario.navigator().index();
        let allowable = scenario.allowable().as_array();
        let reference = frame.navigator_reference(scenario);
        let count = self.uavs.as_ref().map_or(self.sample, Vec::len);
        for j in 0..count {
            let i = self.uavs.as_ref().map_or(j, |u| u[j]);
            let Some(s) = frame.states.get(i) else { continue };
            if !frame.active[i] {
                continue;
            }
            let error = if i == nav {
                [0.0; 6]
            } else {
                formation_error_to(scenario, frame.formation(scenario), frame.states, &reference, i)
            };
            let (outcome, in_envelope) = match frame.uavs[i].outcome {
                Some(o) => (o.label(), o == crate::measure::observer::StepOutcome::Held),
                None if i == nav => ("navigator", false),
                None if frame.successor.is_some_and(|s| s.0 == i) => ("leads", false),
                None => ("initial", false),
            };
            let within_allowable = error.iter().zip(&allowable).all(|(e, a)| e.abs() <= *a);
            let row =
                TrajectoryRow { t: frame.t, uav: i as u32, state: *s, error, outcome, in_envelope, within_allowable };
            if stream {
                if let Some(sink) = self.sink.as_mut() {
                    sink.row(&row);
                }
            }
            if keep {
                self.rows.push(row);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::observer::UavStep;
    use proxform_scenario::builtin::paper;

    /// Counts the rows it is given.
    struct Count(std::sync::Arc<std::sync::atomic::AtomicUsize>);

    impl RowSink for Count {
        fn row(&mut self, _: &TrajectoryRow) {
            self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
    }

    #[test]
    fn a_long_flight_is_streamed_and_kept_decimated() {
        let sc = paper();
        let states: Vec<State9> = sc.initial().to_vec();
        let uavs = vec![UavStep::default(); 6];
        let active = [true; 6];
        let streamed = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        // A flight of 3·10^6 steps: every 3rd step streamed, every 600th kept.
        let mut t = Trajectory::for_flight(3_000_000, Some(Box::new(Count(streamed.clone()))));
        assert_eq!((t.stream_every, t.keep_every), (3, 600));
        for k in 0..6000 {
            let frame = StepFrame::new(k, k as f64 * 0.1, &states, &uavs, &active);
            t.on_step(&sc, &frame);
        }
        assert_eq!(streamed.load(std::sync::atomic::Ordering::Relaxed), 2000 * 6);
        assert_eq!(t.rows.len(), 10 * 6);
        // A short flight keeps and streams every step.
        let short = Trajectory::for_flight(1000, None);
        assert_eq!((short.stream_every, short.keep_every), (1, 1));
    }
}
