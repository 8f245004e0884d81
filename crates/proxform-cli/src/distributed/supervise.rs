//! The launcher's watch over its agent processes during a flight: every period it starts again
//! an agent process that exited (crashed, killed; at most `--agent-restarts` times each), and
//! it keeps the record of every loss (which agent, when in the flight, how it ended, whether it
//! came back) and of how long each follower flew uncontrolled (without its agent, or on the own
//! clock without commands). [`Supervised`] wraps the world's agents for the engine.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use proxform_core::{Decision, UavId};
use proxform_sim::world::remote::{Agents, Phase, StepRequest};

use super::children::Children;

/// How often the processes are looked at.
const CHECK_EVERY: Duration = Duration::from_millis(200);

/// An agent process lost during the flight.
#[derive(Debug, Clone)]
pub struct Loss {
    /// The agent (`agent of UAV(s) 3`).
    pub label: String,
    /// Run of the batch, and time of flight (s) when it was found gone.
    pub at: (u64, f64),
    /// How it ended (`signal: 9 (SIGKILL)`, `exit status: 2`).
    pub status: String,
    /// Started again (its restart number from 1), or why not.
    pub restarted: Result<u32, String>,
}

/// The world's agents, with the launcher's processes watched.
pub struct Supervised<'a, A: Agents> {
    agents: &'a mut A,
    children: &'a mut Children,
    limit: u32,
    dt_s: f64,
    checked: Instant,
    at: (u64, f64),
    losses: Vec<Loss>,
    uncontrolled: BTreeMap<u32, u64>,
}

impl<'a, A: Agents> Supervised<'a, A> {
    /// `agents` with the processes of `children`, each started again at most `limit` times.
    pub fn new(agents: &'a mut A, children: &'a mut Children, limit: u32, dt_s: f64) -> Self {
        Self {
            agents,
            children,
            limit,
            dt_s,
            checked: Instant::now(),
            at: (0, 0.0),
            losses: Vec::new(),
            uncontrolled: BTreeMap::new(),
        }
    }

    /// The losses (a last look included: a process lost in the flight's last moments is one
    /// too), and per follower (from 1) the time it flew uncontrolled (s).
    pub fn finish(mut self) -> (Vec<Loss>, Vec<(u32, f64)>) {
        for e in self.children.restart_exited(0) {
            let restarted = Err("the flight was over".to_string());
            self.losses.push(Loss { label: e.label, at: self.at, status: e.status.to_string(), restarted });
        }
        let dt = self.dt_s;
        (self.losses, self.uncontrolled.into_iter().map(|(u, n)| (u, n as f64 * dt)).collect())
    }

    fn check(&mut self) {
        if self.checked.elapsed() < CHECK_EVERY {
            return;
        }
        self.checked = Instant::now();
        for e in self.children.restart_exited(self.limit) {
            self.losses.push(Loss {
                label: e.label,
                at: self.at,
                status: e.status.to_string(),
                restarted: e.restarted,
            });
        }
    }
}

impl<A: Agents> Agents for Supervised<'_, A> {
    fn present(&mut self, uav: UavId) -> bool {
        let here = self.agents.present(uav);
        if !here {
            *self.uncontrolled.entry(uav.0 + 1).or_default() += 1;
        }
        here
    }

    fn failsafe(&mut self, uav: UavId) -> bool {
        self.agents.failsafe(uav)
    }

    fn refused(&mut self, uav: UavId) {
        self.agents.refused(uav);
    }

    fn navigator(&mut self, t_s: f64, truth: &proxform_core::State9) -> Option<Decision> {
        self.agents.navigator(t_s, truth)
    }

    fn decide(&mut self, request: &StepRequest<'_>, out: &mut Vec<Decision>) {
        if request.phase == Phase::Fly {
            self.at = (request.run, request.t_s);
        }
        self.check();
        self.agents.decide(request, out);
    }
}
