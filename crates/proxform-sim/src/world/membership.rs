//! Who flies and who leads, for both engines: the faults' schedule in force (removals, joins,
//! sensor faults, radio blackouts), the navigator's succession when it is lost, and slot
//! re-assignment after a loss (`formation.reassign_on_loss`). Each engine keeps one
//! [`Membership`] and hands what it decides to its controllers: the reference engine to its
//! agents ([`proxform_core::Agent::reassign`]), the fast engine to its records.

use std::sync::Arc;

use proxform_core::assignment::{self, Reassignment};
use proxform_core::state::{self, State9};
use proxform_core::succession::TakeOver;
use proxform_core::Formation;
use proxform_scenario::faults::{self as schedule, Fault};
use proxform_scenario::Scenario;

use super::faults::{self, FaultStep};
use super::phases::{slot_on_path, Leading};

/// The slots of a flight after a re-assignment.
#[derive(Debug)]
struct Reassigned {
    /// What the agents were handed.
    assignment: Reassignment,
    /// The formation flown now, indexed by UAV (the one in force relabelled), and the stage it
    /// is of (None: the first formation).
    flown: Arc<Formation>,
    stage: Option<usize>,
    /// The first frame flown with its slots (made at the start of the step before; u64::MAX
    /// when nobody has moved slot).
    at_k: u64,
}

/// Who flies and who leads in one flight.
#[derive(Debug)]
pub struct Membership {
    /// Which UAVs fly now.
    pub active: Vec<bool>,
    /// The sensor faults and the radio's state in force this step.
    pub faults: FaultStep,
    /// Slots re-assigned in flight (None: every UAV flies its own).
    slots: Option<Reassigned>,
    /// When the next re-assignment is due (s): a UAV was lost.
    reassign_due: Option<f64>,
    /// Who leads: the navigator, or its successor after its loss.
    pub lead: assignment::Lead,
    /// When the leader's loss becomes known and its successor takes over (s).
    succession_due: Option<f64>,
    /// The successor's take-over, once it leads.
    take_over: Option<TakeOver>,
    /// An outside controller has flown the navigator in this flight.
    pub navigator_flown_outside: bool,
    /// The successor's move to a new slot while it leads.
    moving: Option<TakeOver>,
}

impl Membership {
    /// Who flies at t = 0 (all but those removed at 0 or joining later), led by the navigator;
    /// a navigator removed at the start is succeeded when the followers' tracks of it end.
    pub fn new(sc: &Scenario) -> Self {
        let active = initially_flying(sc);
        let nav = sc.navigator().index();
        Self {
            succession_due: (!active[nav]).then_some(sc.controller().track_timeout_s),
            active,
            faults: FaultStep { radio_up: true, ..FaultStep::default() },
            slots: None,
            reassign_due: None,
            lead: assignment::Lead::navigator(sc.navigator()),
            take_over: None,
            navigator_flown_outside: false,
            moving: None,
        }
    }

    /// The formation flown since a re-assignment (indexed by UAV), if there was one.
    pub fn reassigned_formation(&self) -> Option<&Formation> {
        self.slots.as_ref().map(|s| &*s.flown)
    }

    /// Whether step `k`'s frame is the first flown with re-assigned slots.
    pub fn reassigned_at(&self, k: u64) -> bool {
        self.slots.as_ref().is_some_and(|s| s.at_k == k)
    }

    /// The formation flown at `t`, indexed by UAV.
    pub fn flown<'a>(&'a self, sc: &'a Scenario, t: f64) -> &'a Arc<Formation> {
        match &self.slots {
            Some(s) => &s.flown,
            None => sc.formation_at(t),
        }
    }

    /// The dependency tables flown at `t` (indexed by UAV).
    pub fn tables<'a>(&'a self, sc: &'a Scenario, t: f64) -> &'a [proxform_core::DependencySet] {
        match &self.slots {
            Some(s) => &s.assignment.tables,
            None => sc.dependencies_at(t),
        }
    }

    /// Who leads at `t`, as the engines fly it.
    pub(crate) fn leading<'a>(&'a self, sc: &'a Scenario, t: f64) -> Leading<'a> {
        Leading {
            uav: self.lead.leader.index(),
            formation: self.flown(sc, t),
            take_over: self.take_over,
            moving: self.moving,
            flown_outside: self.navigator_flown_outside,
        }
    }

    /// Where the successor, once it leads, carries the navigator's slot: the planned path's
    /// position (starting at `start`) moved by the successor's own distance from its target.
    pub fn carried(&self, sc: &Scenario, t: f64, (start, current): ([f64; 3], &[State9])) -> Option<[f64; 3]> {
        let l = self.lead.leader.index();
        if self.lead.leader == self.lead.navigator || !self.active[l] {
            return None;
        }
        let leading = self.leading(sc, t);
        // Its take-over's gap is the formation's own drift; a move to a new slot is planned.
        let (target, on_path) = (leading.slot(sc, start, t), sc.path().state_at(t, start));
        let at = &current[l];
        Some(std::array::from_fn(|k| on_path[state::X + k] + at[state::X + k] - target[state::X + k]))
    }

    /// The schedule at `t`: removals, joins (a UAV that joins appears in its slot around the
    /// navigator, or the formation's estimate of it, in `current`), and the sensor and radio
    /// faults in force now; `own(current, i)` is UAV `i`'s own measurement now (where a
    /// sensor that sticks freezes).
    pub fn apply_schedule(
        &mut self,
        sc: &Scenario,
        t: f64,
        (start, current): ([f64; 3], &mut [State9]),
        own: impl Fn(&[State9], usize) -> State9,
    ) {
        if sc.faults().is_empty() {
            return;
        }
        // Whether each UAV with a removal or a join flies now: every one of its faults must
        // allow it (one pass over the schedule, not one per fault).
        let mut flies = std::collections::BTreeMap::new();
        for f in sc.faults() {
            if let Fault::Remove { uav, .. } | Fault::Join { uav, .. } = *f {
                let now = schedule::allows(f, t);
                flies.entry(uav.index()).and_modify(|a: &mut bool| *a &= now).or_insert(now);
            }
        }
        for f in sc.faults() {
            match *f {
                Fault::Remove { uav, .. } => {
                    let now = flies[&uav.index()];
                    // The others learn of a loss when their tracks of it end.
                    let due = t + sc.controller().track_timeout_s;
                    if self.active[uav.index()] && !now && sc.reassign_on_loss().is_some() {
                        self.reassign_due = Some(self.reassign_due.map_or(due, |d| d.min(due)));
                    }
                    if self.active[uav.index()] && !now && uav == self.lead.leader {
                        self.succession_due = Some(due);
                    }
                    self.active[uav.index()] = now;
                }
                Fault::Join { uav, offset_m, .. } => {
                    let i = uav.index();
                    let now = flies[&i];
                    if now && !self.active[i] {
                        // Appears in its slot relative to the navigator (or to the formation's
                        // estimate of it), shifted by the offset.
                        let f = self.flown(sc, t);
                        let carried = self.carried(sc, t, (start, current));
                        let reference =
                            crate::measure::observer::navigator_reference(sc, f, current, &self.active, carried);
                        let mut s = slot_state(sc, f, i, &reference);
                        s[state::X] += offset_m.x;
                        s[state::Y] += offset_m.y;
                        s[state::Z] += offset_m.z;
                        current[i] = s;
                    }
                    self.active[i] = now;
                }
                _ => {}
            }
        }
        let current = &*current;
        self.faults = faults::gather(sc.faults(), t, &self.faults, |i| own(current, i));
    }

    /// Slot re-assignment (`formation.reassign_on_loss`) and the navigator's succession, when
    /// a loss becomes known, and at every change of formation after one, at `t` (step `k`). A
    /// lost leader's successor ([`assignment::successor`]) flies the navigator's path at its
    /// own slot from then on, and every table that named the navigator names it. With
    /// re-assignment, from the positions of the UAVs and of the slots now, every UAV still
    /// flying gets its slot by [`assignment::after_loss`]. The controllers fly the result from
    /// this step on (so a later formation's vacated slot is at its own edge): what it returns
    /// is for every active follower (None: nothing changes now); the formation flown is kept
    /// relabelled for the measures.
    pub fn reassign(
        &mut self,
        sc: &Scenario,
        (t, k): (f64, u64),
        (start, current): ([f64; 3], &[State9]),
    ) -> Option<Reassignment> {
        let stage = sc.schedule().stages().iter().rposition(|s| t >= s.at_s - 1e-9);
        let (formation, tables) = match stage {
            Some(k) => {
                let s = &sc.schedule().stages()[k];
                (&*s.formation, &s.dependencies[..])
            }
            None => (&**sc.formation(), sc.dependencies()),
        };
        let known = |due: Option<f64>| due.is_some_and(|due| t >= due - 1e-9);
        let by = sc.reassign_on_loss();
        let restage = self.slots.as_ref().is_some_and(|s| s.stage != stage);
        let reassign = by.is_some() && known(self.reassign_due);
        let succession = known(self.succession_due);
        if !(reassign || succession || restage) {
            return None;
        }
        if reassign {
            self.reassign_due = None;
        }
        let n = sc.len();
        let slot_of: Vec<usize> =
            self.slots.as_ref().map_or_else(|| (0..n).collect(), |s| s.assignment.slot_of.to_vec());
        let flown = self.slots.as_ref().map_or(formation, |s| &*s.flown);
        let mut lead = self.lead;
        if succession {
            self.succession_due = None;
            let flown_tables = self.slots.as_ref().map_or(tables, |s| &s.assignment.tables[..]);
            if let Some(next) = proxform_core::succession::successor(flown, flown_tables, lead.leader, &self.active) {
                lead.leader = next;
                let i = next.index();
                let slot = slot_on_path(sc, flown, start, i, t);
                self.take_over = Some(TakeOver::for_controller(t, &current[i], &slot, sc.controller()));
            }
        }
        let new = match by {
            Some(by) if reassign || restage => {
                let carried = self.carried(sc, t, (start, current));
                let reference =
                    crate::measure::observer::navigator_reference(sc, flown, current, &self.active, carried);
                let nav_slot = &formation.slots[slot_of[sc.navigator().index()]];
                let at = |s: &State9| [s[state::X], s[state::Y], s[state::Z]];
                let slot_at: Vec<[f64; 3]> = formation
                    .slots
                    .iter()
                    .map(|slot| at(&(reference + formation.w(slot, nav_slot, &reference))))
                    .collect();
                let uav_at: Vec<[f64; 3]> = current.iter().map(at).collect();
                assignment::after_loss(
                    formation,
                    tables,
                    sc.navigator(),
                    (&slot_of, &self.active),
                    (&uav_at, &slot_at),
                    by,
                )
            }
            _ => slot_of.clone(),
        };
        // The measures judge a re-assignment as a change of formation; a succession alone
        // moves nobody.
        let moved = (by.is_some() && (reassign || restage)) || new != slot_of;
        let at_k = if moved { k + 1 } else { self.slots.as_ref().map_or(u64::MAX, |s| s.at_k) };
        let r = Reassignment::new(formation, tables, new, self.active.clone(), lead).moving(moved || restage);
        // A successor whose slot changes moves to it from where its old one had it.
        let l = lead.leader.index();
        let before = (lead.leader != lead.navigator).then(|| match lead.leader == self.lead.leader {
            true => self.leading(sc, t).slot(sc, start, t),
            // A successor named now: from its slot in the formation it took over.
            false => slot_on_path(sc, flown, start, l, t),
        });
        if let Some(before) = before {
            let after = slot_on_path(sc, &r.formation, start, l, t);
            if (state::position(&after) - state::position(&before)).norm() > 1e-9 {
                self.moving = Some(TakeOver::for_controller(t, &before, &after, sc.controller()));
            }
        }
        self.lead = lead;
        // (Its tables, slots and formation are shared, not copied.)
        self.slots = Some(Reassigned { flown: r.formation.clone(), assignment: r.clone(), stage, at_k });
        Some(r)
    }
}

/// Which UAVs fly at t = 0: all but those removed at 0 or joining later (one pass over the
/// schedule).
fn initially_flying(sc: &Scenario) -> Vec<bool> {
    let mut active = vec![true; sc.len()];
    for f in sc.faults() {
        if let Some(u) = f.uav().filter(|_| matches!(f, Fault::Remove { .. } | Fault::Join { .. })) {
            active[u.index()] &= schedule::allows(f, 0.0);
        }
    }
    active
}

/// UAV `i`'s slot in formation `f` (indexed by UAV) around the navigator's state `nav`.
fn slot_state(sc: &Scenario, f: &Formation, i: usize, nav: &State9) -> State9 {
    nav + f.w(&f.slots[i], &f.slots[sc.navigator().index()], nav)
}
