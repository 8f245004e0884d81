//! Agents outside the engine: the split path (sense every follower, ask the agents once, then
//! actuate and propagate) flies exactly the fused path when the agents step as the in-process
//! ones, whatever the scenario's faults, radio, vehicle or own-state filter; an agent that
//! does not answer holds its course.

use proxform_core::Decision;
use proxform_scenario::builtin::{paper_spec, spec_by_name};
use proxform_scenario::spec::FaultSpec;
use proxform_scenario::{Scenario, ScenarioSpec};
use proxform_sim::world::remote::{holding, Agents, LocalAgents, Phase, StepRequest};
use proxform_sim::{Observer, RunOptions, Simulation, StepFrame};

/// Every state of every step.
#[derive(Default)]
struct Record(Vec<proxform_core::State9>);

impl Observer for Record {
    fn on_step(&mut self, _: &Scenario, frame: &StepFrame<'_>) {
        self.0.extend_from_slice(frame.states);
    }
}

fn flights(sc: &Scenario, seed: u64) -> (Vec<proxform_core::State9>, Vec<proxform_core::State9>) {
    let mut fused = Record::default();
    Simulation::new(sc, RunOptions::default(), seed, 0).run(&mut fused);
    let mut split = Record::default();
    Simulation::with_agents(sc, RunOptions::default(), (seed, 0), Box::new(LocalAgents::new(sc))).run(&mut split);
    (fused.0, split.0)
}

fn scenario(spec: ScenarioSpec) -> Scenario {
    Scenario::try_from(spec).expect("valid")
}

#[test]
fn the_split_path_flies_the_fused_path_bit_for_bit() {
    let short = |mut s: ScenarioSpec| {
        s.duration_s = Some(30.0);
        s
    };
    let cases = [
        ("paper", short(paper_spec())),
        (
            "faults, filter and radio",
            short(paper_spec().with(|s| {
                s.controller.own_filter_gain = Some(0.6);
                s.radio.beacons = Some(vec![1]);
                s.radio.delay_s = Some(0.2);
                s.radio.loss = Some(0.2);
                s.sensing.dropout = Some(0.2);
                s.fault = vec![
                    FaultSpec::remove(2, 10.0),
                    FaultSpec {
                        kind: Some("glitch".into()),
                        uav: Some(4),
                        at_s: Some(5.0),
                        duration_s: Some(2.0),
                        offset_m: Some([0.0, 20.0, 0.0]),
                    },
                ];
            })),
        ),
        ("fixed wing in turbulence", short(spec_by_name("fixed-wing-v", None).expect("built in"))),
    ];
    for (name, spec) in cases {
        let sc = scenario(spec);
        let (fused, split) = flights(&sc, 3);
        assert_eq!(fused.len(), split.len(), "{name}");
        assert!(fused == split, "{name}: the split path differs");
    }
}

/// Agents of which one never answers.
struct Silent {
    inner: LocalAgents,
    silent: u32,
    warm_requests: usize,
}

impl Agents for Silent {
    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        self.inner.decide(request, out);
        self.warm_requests += usize::from(request.phase == Phase::Warm);
        for (j, u) in request.sensed.uavs.iter().enumerate() {
            if u.0 == self.silent {
                out[j] = holding();
            }
        }
    }
}

#[test]
fn a_silent_agent_holds_its_course_and_the_others_still_decide() {
    let sc = scenario(paper_spec().with(|s| s.duration_s = Some(20.0)));
    let agents = Silent { inner: LocalAgents::new(&sc), silent: 2, warm_requests: 0 };
    let mut sim = Simulation::with_agents(&sc, RunOptions::default(), (1, 0), Box::new(agents));
    let start = sim.states()[2];
    for _ in 0..50 {
        sim.step();
    }
    // UAV3 kept its velocity and attitude: no input ever reached it.
    let now = sim.states()[2];
    assert_eq!(&now.as_slice()[3..], &start.as_slice()[3..]);
    let (fused, _) = flights(&sc, 1);
    // The others decided (their states differ from a formation that never adjusts).
    assert!(fused.len() > 6 * 50);
}

/// Agents of which one answers with non-finite or huge numbers (a broken or hostile sender).
struct Poisoned {
    inner: LocalAgents,
    uav: u32,
    value: f64,
    /// The UAVs whose decisions the world refused, as it said.
    refused: std::rc::Rc<std::cell::RefCell<Vec<u32>>>,
}

impl Agents for Poisoned {
    fn refused(&mut self, uav: proxform_core::UavId) {
        self.refused.borrow_mut().push(uav.0);
    }

    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        self.inner.decide(request, out);
        for (j, u) in request.sensed.uavs.iter().enumerate() {
            if u.0 == self.uav {
                out[j].input[1] = self.value;
                out[j].outcome = proxform_core::Outcome::Adjusted { normalised_sq: 1.0 };
            }
        }
    }
}

#[test]
fn a_decision_with_a_non_finite_or_impossible_number_is_never_applied() {
    let sc = scenario(paper_spec().with(|s| s.duration_s = Some(20.0)));
    // Non-finite, and finite far beyond what the vehicle can do in a period (a UAV flown on
    // 1e300 ended at 2.9e303 m, then NaN).
    for value in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300, -1e6] {
        let refused = std::rc::Rc::default();
        let agents = Poisoned { inner: LocalAgents::new(&sc), uav: 2, value, refused: std::rc::Rc::clone(&refused) };
        let mut sim = Simulation::with_agents(&sc, RunOptions::default(), (1, 0), Box::new(agents));
        let start = sim.states()[2];
        for _ in 0..50 {
            sim.step();
        }
        // Each refusal was said, for that UAV alone, every flight step.
        assert_eq!(*refused.borrow(), vec![2; 50], "{value}");
        // UAV3 held its course (as a UAV whose agent does not answer), its state finite.
        let now = sim.states()[2];
        assert!(now.iter().all(|v| v.is_finite()), "{value}: {now:?}");
        assert_eq!(&now.as_slice()[3..], &start.as_slice()[3..], "{value}");
    }
    assert!(!Decision { input: proxform_core::Input::repeat(f64::NAN), ..holding() }.is_finite());
    assert!(holding().is_finite());
}

/// Agents of which one is gone for a while.
struct Away {
    inner: LocalAgents,
    uav: u32,
    away: std::ops::Range<u64>,
    step: u64,
}

impl Agents for Away {
    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        if request.phase == Phase::Fly {
            self.step = request.k;
        }
        self.inner.decide(request, out);
    }

    fn present(&mut self, uav: proxform_core::UavId) -> bool {
        // Asked before the step's decisions: the step about to fly is `self.step + 1`.
        uav.0 != self.uav || !self.away.contains(&(self.step + 1))
    }
}

/// Whether UAV3 flies, and flies uncontrolled, at each step; its error to its slot 10 s after
/// its agent came back.
#[derive(Default)]
struct Flying(Vec<(bool, bool)>, Vec<proxform_core::State9>);

impl Observer for Flying {
    fn on_step(&mut self, sc: &Scenario, frame: &StepFrame<'_>) {
        self.0.push((frame.active[2], frame.uavs[2].uncontrolled));
        if frame.k == 150 {
            let nav = frame.states[0];
            self.1.push(sc.slot_state(2, &nav) - frame.states[2]);
        }
    }
}

#[test]
fn a_follower_whose_agent_is_gone_flies_on_uncontrolled_and_the_run_does_not_pass() {
    let sc = scenario(paper_spec().with(|s| s.duration_s = Some(20.0)));
    let agents = Away { inner: LocalAgents::new(&sc), uav: 2, away: 20..50, step: 0 };
    let mut seen = Flying::default();
    let mut metrics = proxform_sim::RunMetrics::new(&sc);
    Simulation::with_agents(&sc, RunOptions::default(), (1, 0), Box::new(agents)).run(&mut (&mut seen, &mut metrics));
    assert!(seen.0.iter().all(|(flies, _)| *flies), "UAV3 stays in the flight");
    let gone: Vec<bool> = seen.0.iter().map(|(_, u)| *u).collect();
    assert!(!gone[..20].iter().any(|u| *u) && !gone[51..].iter().any(|u| *u), "controlled before and after");
    assert!(gone[21..50].iter().all(|u| *u), "uncontrolled while its agent is gone: {:?}", &gone[15..55]);
    // Back in its slot once its agent is (it was never moved there).
    let e = seen.1[0];
    assert!(e[0].abs() < 0.5 && e[1].abs() < 0.6 && e[2].abs() < 0.2, "UAV3 back in its slot: {e:?}");
    let r = metrics.finish(0, sc.duration_s());
    assert!((r.uncontrolled_s - 3.0).abs() < 0.15, "{}", r.uncontrolled_s);
    assert!(!r.pass, "a follower flew 3 s without its agent");
}
