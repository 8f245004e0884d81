//! The proximity formation controller of one UAV (METHOD §2-§7).
//!
//! One call of [`ProximityController::step`] is one update period of the paper's method,
//! written as METHOD §6's numbered steps: it sorts what the UAV perceives into azimuth areas
//! (§2, the information matrix S_i), predicts each kept neighbour (§3) and turns each
//! prediction into an estimate X̂_ij of its own state through the formation offsets (step 1,
//! eq. 10), averages them into X̄_i (step 2, eq. 11), leans on its main references by their
//! dependency degrees in X̂ᴰ_i (step 3), places the envelope centre O_i on the line between the
//! two (step 4), and keeps its course while the course stays inside the envelope (steps 5-6)
//! or computes the predictive input (step 7, eq. 12). With nothing perceived it flies on
//! (step 8). The controller sees only its own state estimate and its observations: it cannot
//! tell a simulator from a network.
//!
//! Every estimate is kept as a deviation from X_hold = F·X_i, the state the UAV will have if
//! it keeps its course: `X̂_ij − X_hold`, and so the centre `O_i − X_hold`. Attitude
//! differences are then small and wrap correctly, and step 6's test is on `X_hold − O_i`.

mod avoid;
mod decision;
mod fusion;
mod params;
mod setup;
mod tracks;

use std::sync::Arc;

pub use avoid::{relative_speed_bound, Avoidance, AvoidanceMemory, CloseWatch};
pub use decision::{Decision, Outcome};
pub use params::{ControllerParams, AVOID_BRAKING_SHARE, AVOID_WATCH, MAX_HORIZON, SEPARATION_SLOT_FRACTION};
pub use setup::ControllerSetup;
pub use tracks::Tracks;

use fusion::{Fusion, Implied};

use crate::error::ConfigError;
use crate::formation::{Formation, FormationSlot};
use crate::observation::{NavigatorReport, Observation, ObservationSource, UavId};
use crate::predictor::NeighbourTracks;
use crate::state::{self, State9, VX, X};
use crate::vehicle::VehicleModel;
use crate::DependencySet;

/// Marks an empty area in the per-area scratch.
const EMPTY: u32 = u32::MAX;
/// Marks an area candidate that is a coasting track (its slot in the low bits), not an
/// observation index.
const TRACK: u32 = 1 << 31;

/// The controller of one UAV.
#[derive(Debug, Clone)]
pub struct ProximityController {
    id: UavId,
    setup: Arc<ControllerSetup>,
    formation: Arc<Formation>,
    dependency: DependencySet,
    tracks: NeighbourTracks,
    /// The step's working memory, allocated once.
    scratch: StepScratch,
    /// The navigator, when known: the robust fusion never leaves it out, and weighs the others
    /// against the UAVs no farther from it than this one.
    navigator: Option<UavId>,
    /// Collision avoidance's working memory (only with `avoid_m` > 0): allocated once.
    avoidance: Option<Box<Avoidance>>,
    /// The formation's turn as this UAV sees it, for the setpoint lead (only for a vehicle that
    /// lags its setpoints, in a formation that turns as one body).
    trend: Option<Box<TurnTrend>>,
    /// With relative sensing, the own measurement of the last period: what it moved by beyond
    /// its measured velocity is its position fix's error moving, which moves every onboard
    /// observation alike.
    own_frame: Option<Box<OwnFix>>,
}

/// Up to this many observations a step, the controller keeps the UAVs it has counted in a short
/// list on the stack ([`FewIds`]); beyond, it looks them up in [`COUNTED`].
const SCAN_UP_TO: usize = 32;

thread_local! {
    /// With more than [`SCAN_UP_TO`] observations in a step, the UAVs of which it holds one
    /// that counts (not a close-range detection, not left out of the frame): a lookup per
    /// observation, where a search of the others made a swarm broadcasting to all quadratic
    /// per UAV. The thread's scratch (cleared at each use), so a controller keeps no memory
    /// for it.
    static COUNTED: std::cell::RefCell<std::collections::HashSet<u32>> = std::cell::RefCell::default();
}

/// Up to [`SCAN_UP_TO`] UAV ids in an open-addressed table of twice as many slots (a
/// multiplicative hash, linear probing): a UAV is told counted or not in one or two probes,
/// where a search of the ids took one per id counted.
struct FewIds {
    slots: [u32; FEW_SLOTS],
    n: usize,
    /// Whether the id that marks a free slot was counted (held apart: no formation has that
    /// many UAVs, but an id is what the caller says it is).
    free_id: bool,
}

/// The slots of [`FewIds`]: twice [`SCAN_UP_TO`], a power of two.
const FEW_SLOTS: usize = 2 * SCAN_UP_TO;
/// An empty slot of [`FewIds`].
const FREE_ID: u32 = u32::MAX;

impl FewIds {
    fn new() -> Self {
        Self { slots: [FREE_ID; FEW_SLOTS], n: 0, free_id: false }
    }

    /// The slot `id` hashes to (Fibonacci hashing: the top bits of id × 2³²/φ).
    #[inline]
    fn home(id: u32) -> usize {
        (id.wrapping_mul(0x9E37_79B9) >> (32 - FEW_SLOTS.trailing_zeros())) as usize
    }

    /// Whether `id` is counted.
    #[inline]
    fn contains(&self, id: u32) -> bool {
        if id == FREE_ID {
            return self.free_id;
        }
        let mut s = Self::home(id);
        loop {
            match self.slots[s] {
                x if x == id => return true,
                FREE_ID => return false,
                _ => s = (s + 1) & (FEW_SLOTS - 1),
            }
        }
    }

    /// Counts `id`; false when it was counted already. At most [`SCAN_UP_TO`] ids are kept
    /// (the table stays at most half full, so a probe always ends).
    #[inline]
    fn insert(&mut self, id: u32) -> bool {
        if id == FREE_ID {
            return !std::mem::replace(&mut self.free_id, true);
        }
        let mut s = Self::home(id);
        loop {
            match self.slots[s] {
                x if x == id => return false,
                FREE_ID => break,
                _ => s = (s + 1) & (FEW_SLOTS - 1),
            }
        }
        if self.n < SCAN_UP_TO {
            self.slots[s] = id;
            self.n += 1;
        }
        true
    }
}

/// The UAVs counted in a step: few on the stack, many in the thread's set.
enum Counted<'a> {
    Few(&'a mut FewIds),
    Many(&'a mut std::collections::HashSet<u32>),
}

impl Counted<'_> {
    #[inline]
    fn insert(&mut self, id: u32) -> bool {
        match self {
            Counted::Few(f) => f.insert(id),
            Counted::Many(c) => c.insert(id),
        }
    }

    #[inline]
    fn contains(&self, id: u32) -> bool {
        match self {
            Counted::Few(f) => f.contains(id),
            Counted::Many(c) => c.contains(&id),
        }
    }
}

/// A UAV's own measured position and velocity at a time: with relative sensing, the frame its
/// tracks are in (every onboard observation is its own measured position plus the
/// neighbour's relative one). Kept by [`ProximityController`] and per UAV by an engine that
/// keeps its tracks itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OwnFix {
    t: f64,
    pos: [f64; 3],
    vel: [f64; 3],
}

impl OwnFix {
    /// The fix of the UAV's own state estimate `own` at `now_s`.
    pub fn new(now_s: f64, own: &State9) -> Self {
        Self { t: now_s, pos: [own[X], own[X + 1], own[X + 2]], vel: [own[VX], own[VX + 1], own[VX + 2]] }
    }

    /// Follows the fix to `next`: how far the UAV's tracks move with it (what the own measured
    /// position moved beyond its measured velocity since this fix, trapezoid rule), so that a
    /// track coasting from then and the UAV's own state keep the same error; None when the
    /// fixes lie more than `max_s` apart (or not in order) or the move is not finite.
    pub fn follow(&mut self, next: OwnFix, max_s: f64) -> Option<[f64; 3]> {
        let h = next.t - self.t;
        let d: [f64; 3] = std::array::from_fn(|k| next.pos[k] - self.pos[k] - 0.5 * h * (self.vel[k] + next.vel[k]));
        *self = next;
        (h > 0.0 && h <= max_s && d.iter().all(|x| x.is_finite())).then_some(d)
    }

    /// `state` (in the UAV's tracks' frame) relative to the UAV's own position at `now`: its
    /// fix carried there at the fix's velocity.
    pub fn relative(&self, now: f64, mut state: State9) -> State9 {
        let h = now - self.t;
        for k in 0..3 {
            state[X + k] -= self.pos[k] + self.vel[k] * h;
        }
        state
    }
}

/// The formation's turn rate as one UAV sees it (the mean of its neighbours' turn rates) and
/// that rate's rate of change, low-passed over [`ControllerParams::turn_trend_s`]: a slot at
/// `r` from its reference moves with the tangential acceleration `ω̇ × r` as a turn begins or
/// ends, which a vehicle that lags its setpoints must be asked for ahead. Kept per UAV from
/// one step to the next.
#[derive(Debug, Clone, Copy, Default)]
pub struct TurnTrend {
    /// When the mean was last taken (s).
    t: f64,
    /// The mean turn rate then (rad/s).
    omega: f64,
    /// Its rate of change, low-passed (rad/s²).
    omega_dot: f64,
    /// A mean was taken.
    seen: bool,
}

impl TurnTrend {
    /// Takes this step's mean turn rate `omega` at `now` (None: no neighbour gave one).
    fn update(&mut self, now: f64, omega: Option<f64>, smoothing_s: f64) {
        let Some(omega) = omega else {
            *self = Self::default();
            return;
        };
        let h = now - self.t;
        if self.seen && h > 0.0 {
            let k = 1.0 - (-h / smoothing_s).exp();
            self.omega_dot += k * ((omega - self.omega) / h - self.omega_dot);
        }
        *self = Self { t: now, omega, omega_dot: self.omega_dot, seen: true };
    }
}

/// Steps 1-3 accumulated over the perceived neighbours, each estimate as `X̂_ij − X_hold`.
#[derive(Debug, Clone, Copy)]
struct Estimates {
    /// Σ f_j·(X̂_ij − X_hold) over the occupied areas, f_j the neighbour's weight (1 when
    /// measured, fading while it coasts).
    sum_bar: State9,
    /// Σ f_j over the occupied areas.
    w_bar: f64,
    /// Occupied areas.
    n_bar: u16,
    /// Σ c_ij·f_j·(X̂_ij − X_hold) over the main references perceived.
    sum_dep: State9,
    /// Σ c_ij·f_j.
    c_sum: f64,
    /// Main references perceived.
    main_refs: u16,
    /// Separation keeping: how far to move away from neighbours that come too close (m).
    push: [f64; 3],
    /// Neighbours the robust fusion left out.
    isolated: u16,
}

impl Estimates {
    fn new() -> Self {
        Self {
            sum_bar: State9::zeros(),
            w_bar: 0.0,
            n_bar: 0,
            sum_dep: State9::zeros(),
            c_sum: 0.0,
            main_refs: 0,
            push: [0.0; 3],
            isolated: 0,
        }
    }

    /// Adds one neighbour's estimate to the sums it belongs to: X̄_i's when it stands for an
    /// area, X̂ᴰ_i's when it is a main reference.
    fn add(&mut self, n: &Implied) {
        if n.in_area {
            self.sum_bar += n.f * n.x_hat;
            self.w_bar += n.f;
            self.n_bar += 1;
        }
        if let Some(c) = n.c {
            self.add_reference(c, n.f, &n.x_hat);
        }
    }

    /// Takes a neighbour's estimate: straight into the sums, or, with the robust fusion, into
    /// its list to be weighed first.
    #[inline]
    fn take(&mut self, fusion: &mut Option<Box<Fusion>>, n: Implied) {
        match fusion {
            Some(fu) => fu.implied.push(n),
            None => self.add(&n),
        }
    }

    /// Adds a main reference's estimate (degree `c`, weight `f`) to X̂ᴰ_i's sums.
    fn add_reference(&mut self, c: f64, f: f64, x_hat_ij: &State9) {
        self.sum_dep += (c * f) * x_hat_ij;
        self.c_sum += c * f;
        self.main_refs += 1;
    }
}

impl ProximityController {
    /// A controller for UAV `id` of `formation`.
    pub fn new(
        id: UavId,
        setup: Arc<ControllerSetup>,
        formation: Arc<Formation>,
        dependency: DependencySet,
    ) -> Result<Self, ConfigError> {
        if formation.slot(id).is_none() {
            return Err(ConfigError::UnknownUav { id, size: formation.len() });
        }
        for &(r, _) in dependency.refs() {
            if formation.slot(r).is_none() {
                return Err(ConfigError::BadReference { owner: id, reference: r, reason: "not in the formation" });
            }
        }
        let p = &setup.params;
        let slots = p.areas.areas + dependency.refs().len();
        let tracks = NeighbourTracks::new(p.predictor, slots, p.track_timeout_s, p.coast_accel_s)
            .with_carry(setup.carry(formation.frame));
        let avoidance = p.avoid_m.filter(|&d| d > 0.0).map(|d| Box::new(Avoidance::new(d, setup.braking_mps2)));
        let scratch = StepScratch::new(p, slots);
        let trend = setup.keeps_turn_trend().then(Box::default);
        Ok(Self {
            id,
            setup,
            formation,
            dependency,
            tracks,
            scratch,
            navigator: None,
            avoidance,
            trend,
            own_frame: None,
        })
    }

    /// Flies under a new leader (the navigator's successor) with table `dependency` in
    /// `formation` (the same slots, relabelled): what it knows of its neighbours, its tracks
    /// and its turn trend, is kept (they are the same UAVs, where they were).
    pub fn lead_by(
        &mut self,
        leader: UavId,
        formation: Arc<Formation>,
        dependency: DependencySet,
    ) -> Result<(), ConfigError> {
        for &(r, _) in dependency.refs() {
            if formation.slot(r).is_none() {
                return Err(ConfigError::BadReference { owner: self.id, reference: r, reason: "not in the formation" });
            }
        }
        self.tracks.grow_to(self.setup.params.areas.areas + dependency.refs().len());
        // The lost leader's track (carried by the plan) stands for its successor, moved by the
        // offset between their slots, until reports of the successor arrive: a UAV that knew
        // the leader only through relays would otherwise lean on nobody while the relays of
        // the successor reach it hop by hop (METHOD §8, "Navigator succession").
        if let Some(lost) = self.navigator.filter(|&n| n != leader) {
            if let (Some(from), Some(to)) = (self.formation.slot(lost).copied(), self.formation.slot(leader).copied()) {
                let old = &self.formation;
                self.tracks.relabel(lost, leader, |s| old.w(&to, &from, s));
            }
        }
        self.formation = formation;
        self.dependency = dependency;
        self.navigator = self.formation.slot(leader).map(|_| leader);
        Ok(())
    }

    /// Names the formation's navigator: the robust fusion (`isolation_gate`) never leaves it
    /// out, and takes its median over the UAVs whose slots are no farther from the navigator's
    /// than this UAV's own, so that the UAVs that follow this one cannot outvote those it
    /// follows. Without it, every neighbour counts and may be left out.
    pub fn with_navigator(mut self, navigator: UavId) -> Self {
        self.navigator = self.formation.slot(navigator).map(|_| navigator);
        self
    }

    /// What this UAV knows of the navigator at `now`, to forward over the radio
    /// (`radio.relay_navigator`): its track (the filtered state at its last measurement, and
    /// that measurement's age in s). With relative sensing its tracks are in the frame of its
    /// own last fix: the position is less the UAV's own at `now` (its last fix carried there
    /// at the fix's velocity, one period at most). None when the navigator is not named or not
    /// tracked (heard within the track timeout, measured within `relay_max_age_s`; or,
    /// relative, before a fix).
    pub fn navigator_report(&self, now: f64) -> Option<NavigatorReport> {
        let navigator = self.navigator?;
        let (state, age_s) = navigator_track(&self.setup.params, &self.tracks, navigator, now)?;
        if !self.setup.params.relative_sensing {
            return Some(NavigatorReport { state, age_s, relative: false });
        }
        // The track at its last measurement, less the UAV's own position now (its last fix, in
        // whose frame its tracks are, carried to now at the fix's velocity).
        let fix = self.own_frame.as_deref()?;
        Some(NavigatorReport { state: fix.relative(now, state), age_s, relative: true })
    }

    /// A controller with its own [`ControllerSetup`] (convenient for a single UAV).
    pub fn standalone(
        id: UavId,
        params: ControllerParams,
        formation: Arc<Formation>,
        dependency: DependencySet,
        vehicle: VehicleModel,
    ) -> Result<Self, ConfigError> {
        Self::new(id, ControllerSetup::new(params, vehicle)?, formation, dependency)
    }

    /// This controller's UAV.
    pub fn id(&self) -> UavId {
        self.id
    }

    /// Its parameters.
    pub fn params(&self) -> &ControllerParams {
        &self.setup.params
    }

    /// Its vehicle model.
    pub fn vehicle(&self) -> &VehicleModel {
        &self.setup.vehicle
    }

    /// The shared setup.
    pub fn setup(&self) -> &ControllerSetup {
        &self.setup
    }

    /// Bytes this controller holds on the heap (shared setup and formation excluded).
    pub fn heap_bytes(&self) -> usize {
        self.tracks.heap_bytes() + self.scratch.heap_bytes() + self.avoidance.as_ref().map_or(0, |a| a.heap_bytes())
    }

    /// One update period at time `now_s`: `own` is the UAV's estimate of its own state X_i,
    /// `observations` what it perceives of the others (a UAV reported more than once
    /// counts once; its further reports feed its track).
    pub fn step(&mut self, now_s: f64, own: &State9, observations: &[Observation]) -> Decision {
        if self.formation.slot(self.id).is_none() {
            return Decision::alone();
        }
        if self.setup.params.relative_sensing {
            self.follow_own_frame(now_s, own);
        }
        let Self { id, setup, formation, dependency, tracks, scratch, navigator, avoidance, trend, .. } = self;
        let uav = UavView {
            id: *id,
            setup,
            formation,
            dependency,
            navigator: *navigator,
            tracks,
            avoidance: avoidance.as_deref_mut(),
            trend: trend.as_deref_mut(),
        };
        uav.step(scratch, now_s, own, observations)
    }

    /// Relative sensing: every onboard observation is the UAV's own measured position plus the
    /// neighbour's relative one, so a change of its own position fix's error (a GNSS bias that
    /// wanders) moves all of them alike. The tracks move with it: by what the own measured
    /// position moved beyond its measured velocity since the last period (trapezoid rule), so
    /// that a track coasting from then and the UAV's own state keep the same error.
    fn follow_own_frame(&mut self, now_s: f64, own: &State9) {
        let now = OwnFix::new(now_s, own);
        match self.own_frame.as_deref_mut() {
            Some(last) => {
                if let Some(d) = last.follow(now, self.setup.params.track_timeout_s) {
                    self.tracks.shift(d);
                }
            }
            None => self.own_frame = Some(Box::new(now)),
        }
    }
}

/// The step's working memory, allocated once: S_i per azimuth area and the robust fusion's
/// list. A controller holds its own; an engine that steps many UAVs keeps one per thread.
#[derive(Debug, Clone)]
pub struct StepScratch {
    /// S_i: per area, index into the observation slice of the nearest UAV (or `EMPTY`, or a
    /// coasting track marked `TRACK`) and its squared distance (f32 is ample to rank
    /// neighbours).
    nearest: Box<[(u32, f32)]>,
    /// Robust fusion's working memory (only with `isolation_gate`).
    fusion: Option<Box<Fusion>>,
}

impl StepScratch {
    /// Working memory for a UAV with `params` and up to `slots` neighbours estimated (its
    /// areas and main references).
    pub fn new(params: &ControllerParams, slots: usize) -> Self {
        let fusion = params
            .isolation_gate
            .map(|_| Box::new(Fusion { implied: Vec::with_capacity(slots), scratch: Vec::with_capacity(slots) }));
        Self { nearest: vec![(EMPTY, 0.0); params.areas.areas].into_boxed_slice(), fusion }
    }

    /// Bytes held on the heap.
    pub fn heap_bytes(&self) -> usize {
        std::mem::size_of_val(&*self.nearest)
            + self.fusion.as_ref().map_or(0, |f| {
                std::mem::size_of::<Fusion>()
                    + f.implied.capacity() * std::mem::size_of::<Implied>()
                    + f.scratch.capacity() * std::mem::size_of::<f64>()
            })
    }
}

/// One UAV as the method's step sees it, over any store of its tracks ([`Tracks`]): who it
/// is, the swarm's setup and formation, its table of main references, and what it keeps from
/// one step to the next. [`ProximityController`] is one UAV's own; an engine that keeps the
/// tracks of many UAVs in its own arrays builds one per update and runs the same step.
#[derive(Debug)]
pub struct UavView<'a, T: Tracks> {
    /// The UAV.
    pub id: UavId,
    /// The swarm's parameters, vehicle and plan.
    pub setup: &'a ControllerSetup,
    /// The formation it keeps.
    pub formation: &'a Formation,
    /// Its main references and their dependency degrees.
    pub dependency: &'a DependencySet,
    /// The formation's navigator, when named ([`ProximityController::with_navigator`]).
    pub navigator: Option<UavId>,
    /// Its tracks of its neighbours.
    pub tracks: &'a mut T,
    /// Collision avoidance's memory (with `avoid_m` > 0).
    pub avoidance: Option<&'a mut Avoidance>,
    /// The formation's turn as this UAV sees it (the turn feed-forward of a vehicle that lags
    /// its setpoints).
    pub trend: Option<&'a mut TurnTrend>,
}

impl<T: Tracks> UavView<'_, T> {
    /// One update period at time `now_s` (METHOD §6): `own` is the UAV's estimate of its own
    /// state X_i, `observations` what it perceives of the others (a UAV reported more than
    /// once counts once; its further reports feed its track).
    #[inline(never)] // a phase of `proxform bench`'s instruction table
    pub fn step(
        mut self,
        scratch: &mut StepScratch,
        now_s: f64,
        own: &State9,
        observations: &[Observation],
    ) -> Decision {
        let Some(slot_i) = self.formation.slot(self.id).copied() else { return Decision::alone() };
        let setup = self.setup;
        let (params, vehicle) = (&setup.params, &setup.vehicle);
        // F·X_i: the state the UAV will have if it keeps its present course.
        let x_hold = vehicle.hold(own, params.dt_s);

        // §2: S_i, the nearest perceived UAV in each azimuth area (§3: a repeated report of a
        // neighbour updates its track and takes no place of its own).
        self.sort_into_areas(&mut scratch.nearest, now_s, own, observations);
        // Steps 1-3: X̂_ij per neighbour, accumulated into X̄_i and X̂ᴰ_i.
        let est = self.estimate(scratch, now_s, own, &slot_i, &x_hold, observations);
        // Step 8: nothing perceived.
        if est.n_bar == 0 && est.main_refs == 0 {
            return Decision::alone();
        }
        // Step 4: the envelope centre O_i (as O_i − X_hold).
        let (mut o_i, goal) = envelope_centre(params, &est, params.stop_closing.then_some(setup.braking_mps2));
        // Collision avoidance (beyond the paper): no closing faster than braking can stop.
        if let Some(av) = self.avoidance {
            // Skipped (with the same result) when it remembers nothing and cannot bind.
            if av.remembers() || av.may_bind(vehicle, &x_hold, params.dt_s, &o_i, observations, params.track_timeout_s)
            {
                av.perceive(self.formation, self.id, &slot_i, &x_hold, params, observations);
                av.limit(vehicle, &x_hold, params.dt_s, &mut o_i, &goal);
            }
        }
        // Steps 5-6: keep the course while X_hold lies inside the envelope around O_i.
        let x_hold_minus_o = -o_i;
        let envelope = &params.envelope;
        let (occupied_areas, main_refs, isolated) = (est.n_bar, est.main_refs, est.isolated);
        let gap_sq = (0..3).map(|k| (goal[k] / envelope.thresholds[X + k]).powi(2)).sum();
        let decide = |outcome, input| Decision {
            outcome,
            input,
            occupied_areas,
            main_refs,
            isolated,
            own_suspect: false,
            gap_sq,
            setpoint: None,
        };
        if envelope.contains(&x_hold_minus_o) {
            return decide(Outcome::Held, state::Input::zeros());
        }
        // Step 7: the predictive input within the vehicle's limits.
        let normalised_sq = envelope.normalised_sq(&x_hold_minus_o);
        let input = setup.input_toward(own, &x_hold_minus_o);

        decide(Outcome::Adjusted { normalised_sq }, input)
    }

    /// §2: fills S_i (`nearest`) with the nearest UAV per azimuth area, from the UAV's
    /// own view of the observations; then neighbours perceived recently but missing now coast
    /// on their tracks (§3) into areas that have no fresh observation. Every report of a UAV
    /// after its first one (with a predictor that fuses, the sensor passes a radio report
    /// beside the onboard detection of the same UAV) only feeds its track; the first report
    /// stands for it in the areas.
    fn sort_into_areas(&mut self, nearest: &mut [(u32, f32)], now_s: f64, own: &State9, observations: &[Observation]) {
        match observations.len() > SCAN_UP_TO {
            true => COUNTED.with_borrow_mut(|c| {
                c.clear();
                self.sort_into_areas_with(nearest, now_s, own, observations, Counted::Many(c));
            }),
            false => {
                let mut few = FewIds::new();
                self.sort_into_areas_with(nearest, now_s, own, observations, Counted::Few(&mut few))
            }
        }
    }

    /// [`Self::sort_into_areas`], with the UAVs counted so far.
    fn sort_into_areas_with(
        &mut self,
        nearest: &mut [(u32, f32)],
        now_s: f64,
        own: &State9,
        observations: &[Observation],
        mut counted: Counted<'_>,
    ) {
        let Self { id: me, setup, tracks, .. } = self;
        let me = *me;
        let tracks = &mut **tracks;
        let params = &setup.params;
        let r2 = params.areas.sensing_range_m.powi(2);
        nearest.iter_mut().for_each(|a| a.0 = EMPTY);
        let (sin_yaw, cos_yaw) = own[state::BETA].sin_cos();
        for (k, o) in observations.iter().enumerate() {
            if o.source == ObservationSource::Close {
                continue; // collision avoidance's alone
            }
            if out_of_frame(params, tracks, o, observations, now_s) {
                continue;
            }
            // (A report left out of the frame stands for nothing: a later one of the same UAV,
            // a relay placed in the frame, takes the place.) A UAV observed again: its track
            // takes this one too.
            if !counted.insert(o.id.0) {
                tracks.predict(o, now_s, params.dt_s);
                continue;
            }
            if o.id == me {
                continue;
            }
            let (dx, dy, dz) = (o.state[X] - own[X], o.state[X + 1] - own[X + 1], o.state[X + 2] - own[X + 2]);
            let d2 = dx * dx + dy * dy + dz * dz;
            if o.source == ObservationSource::Onboard && d2 > r2 {
                continue;
            }
            let s = setup.classifier.area(sin_yaw, cos_yaw, dx, dy);
            let a = &mut nearest[s];
            let d2 = d2 as f32;
            if a.0 == EMPTY || d2 < a.1 {
                *a = (k as u32, d2);
            }
        }
        let navigator = self.navigator;
        for s in 0..tracks.slots() {
            let Some((id, _)) = coast(params, tracks, navigator, s, now_s) else { continue };
            if id == me || counted.contains(id.0) {
                continue;
            }
            let x = tracks.state_at(s, now_s);
            let (dx, dy, dz) = (x[X] - own[X], x[X + 1] - own[X + 1], x[X + 2] - own[X + 2]);
            let d2 = dx * dx + dy * dy + dz * dz;
            if d2 > r2 {
                continue;
            }
            // A coasting neighbour only fills an area that has no fresh observation.
            let a = &mut nearest[setup.classifier.area(sin_yaw, cos_yaw, dx, dy)];
            let d2 = d2 as f32;
            if a.0 == EMPTY || (a.0 & TRACK != 0 && d2 < a.1) {
                *a = (TRACK | s as u32, d2);
            }
        }
    }

    /// Steps 1-3: for each neighbour in S_i, its predicted state F·X_j (§3, from its track)
    /// and X̂_ij = F·X_j + W_ij (eq. 10); their weighted sums over the areas (for X̄_i) and over
    /// the main references (for X̂ᴰ_i). Main references perceived outside the areas' nearest
    /// count too (METHOD §6 Choice).
    fn estimate(
        &mut self,
        scratch: &mut StepScratch,
        now_s: f64,
        own: &State9,
        slot_i: &FormationSlot,
        x_hold: &State9,
        observations: &[Observation],
    ) -> Estimates {
        let Self { setup, formation, dependency, tracks, navigator, trend, .. } = self;
        let (params, formation, tracks) = (&setup.params, *formation, &mut **tracks);
        let StepScratch { nearest, fusion } = scratch;
        let navigator = *navigator;
        // The robust fusion's view of a neighbour: whether it may be left out, and whether it
        // counts in the median.
        let nav_slot = navigator.and_then(|n| formation.slot(n)).map(|s| s.offset_m);
        let own_reach = nav_slot.map(|o| (slot_i.offset_m - o).norm());
        let roles = |id: UavId| -> (bool, bool) {
            if Some(id) == navigator {
                return (false, true);
            }
            let upstream = match (nav_slot, own_reach, formation.slot(id)) {
                (Some(o), Some(r), Some(s)) => (s.offset_m - o).norm() <= r + 1e-6,
                _ => true,
            };
            (true, upstream)
        };
        if let Some(fu) = fusion {
            fu.implied.clear();
        }
        let dt = params.dt_s;
        let r2 = params.areas.sensing_range_m.powi(2);
        let separation = params.separation_m.unwrap_or(0.0);
        // The formation turns as one body at the navigator's rate where the UAV perceives it,
        // when turn rates are read from headings: the followers steer their headings toward
        // their references', so theirs lag the navigator's along every chain (a fixed wing's
        // bank, from which its rate is read, shows its own turn at once).
        let heading_rate = !matches!(setup.vehicle, VehicleModel::FixedWing(_));
        let nav_omega = match (params.turn_feedforward && heading_rate, navigator) {
            (true, Some(n)) => {
                observations
                    .iter()
                    .find(|o| {
                        o.id == n
                            && o.source != ObservationSource::Close
                            && !out_of_frame(params, tracks, o, observations, now_s)
                    })
                    .and_then(|o| {
                        // From its track's last measurement before this report (not yet fed) to
                        // this report's: a delayed report is as old as the radio made it.
                        let (before, age) = tracks.report(n, now_s, params.track_timeout_s)?;
                        let span = age - o.age_s;
                        (span > crate::predictor::SAME_INSTANT_S)
                            .then(|| setup.vehicle.turn_rate(&before, &o.state, span))
                    })
            }
            _ => None,
        };
        let motion = Motion {
            turn: params.turn_feedforward.then_some(&setup.vehicle),
            lead_s: setup.vehicle.setpoint_lag_s(),
            omega_dot: trend.as_ref().map_or(0.0, |t| t.omega_dot),
            omega: nav_omega,
            dt,
        };
        // Σ f·ω and Σ f over the neighbours, for the turn's trend.
        let mut turn_sum = (0.0, 0.0);
        // X̂_ij − X_hold of neighbour `id` seen at `x_j` and predicted at `f_x_j`, weighing `f`.
        let mut implied = |id: UavId, x_j: &(State9, f64), f_x_j: &State9, f: f64| {
            let (x_hat, omega) = implied_deviation(formation, &motion, id, (&x_j.0, x_j.1), f_x_j, slot_i, x_hold)?;
            if let Some(w) = omega {
                turn_sum = (turn_sum.0 + f * w, turn_sum.1 + f);
            }
            Some(x_hat)
        };
        // The formation's rigid-body turn and the vehicle's setpoint lead need each neighbour's
        // state now beside its prediction.
        let needs_now = motion.needs_now();
        let mut est = Estimates::new();
        // Steps 1-2 (and 3 for main references in their areas).
        for a in 0..nearest.len() {
            let k = nearest[a].0;
            if k == EMPTY {
                continue;
            }
            let (id, f_x_j, f, x_j) = if k & TRACK != 0 {
                let s = (k & !TRACK) as usize;
                match coast(params, tracks, navigator, s, now_s) {
                    Some((id, f)) => {
                        let x_j = if needs_now { tracks.state_at(s, now_s) } else { State9::zeros() };
                        (id, tracks.state_at(s, now_s + dt), f, (x_j, dt))
                    }
                    None => continue,
                }
            } else {
                let o = &observations[k as usize];
                let f_x_j = tracks.predict(o, now_s, dt);
                (o.id, f_x_j, 1.0, seen_now(tracks, o, (now_s, dt, params.track_timeout_s), needs_now))
            };
            if separation > 0.0 {
                keep_apart(formation, id, &f_x_j, slot_i, x_hold, separation, &mut est.push);
            }
            let Some(x_hat) = implied(id, &x_j, &f_x_j, f) else { continue };
            let (suspect, upstream) = if fusion.is_some() { roles(id) } else { (true, true) };
            est.take(fusion, Implied { x_hat, f, c: dependency.degree(id), in_area: true, suspect, upstream });
        }
        // Step 3: main references perceived but not the nearest in their area.
        for r in 0..dependency.refs().len() {
            let (id, c) = dependency.refs()[r];
            let (f_x_j, f, x_j) = match observations.iter().position(|o| {
                o.id == id
                    && o.source != ObservationSource::Close
                    && !out_of_frame(params, tracks, o, observations, now_s)
            }) {
                Some(k) => {
                    if nearest.iter().any(|a| a.0 == k as u32) {
                        continue; // already counted with its area
                    }
                    let o = &observations[k];
                    if o.source == ObservationSource::Onboard
                        && (state::position(&o.state) - state::position(own)).norm_squared() > r2
                    {
                        continue;
                    }
                    let f_x_j = tracks.predict(o, now_s, dt);
                    (f_x_j, 1.0, seen_now(tracks, o, (now_s, dt, params.track_timeout_s), needs_now))
                }
                None => {
                    // Not observed now: coast on its track, unless its area already did.
                    let Some((s, f)) = tracks.slot_of(id).and_then(|s| {
                        coast(params, tracks, navigator, s, now_s).filter(|c| c.0 == id).map(|c| (s, c.1))
                    }) else {
                        continue;
                    };
                    if nearest.iter().any(|a| a.0 == TRACK | s as u32) {
                        continue;
                    }
                    let x_j = if needs_now { tracks.state_at(s, now_s) } else { State9::zeros() };
                    (tracks.state_at(s, now_s + dt), f, (x_j, dt))
                }
            };
            let Some(x_hat) = implied(id, &x_j, &f_x_j, f) else { continue };
            let (suspect, upstream) = if fusion.is_some() { roles(id) } else { (true, true) };
            est.take(fusion, Implied { x_hat, f, c: Some(c), in_area: false, suspect, upstream });
        }
        if let Some(t) = trend {
            t.update(now_s, (turn_sum.1 > 0.0).then(|| turn_sum.0 / turn_sum.1), params.turn_trend_s);
        }
        // Robust fusion: weigh each estimate by its distance from the others' median, then sum.
        if let (Some(fu), Some(gate)) = (fusion, params.isolation_gate) {
            est.isolated = fu.weigh(&params.envelope.thresholds, gate);
            for n in fu.implied.iter().filter(|n| n.f > 0.0) {
                est.add(n);
            }
        }
        est
    }
}

/// The neighbour of track slot `s` if it coasts at `now_s` (§3), and its weight: up to
/// `coast_s` after a report of it last arrived, weighing `exp(−missing / coast_decay_s)`, so
/// that a UAV that has gone fades out. The navigator, where the plan brings reports forward
/// ([`crate::plan`]), coasts up to `track_timeout_s` at full weight: the plan is its path, so
/// its track carried by the plan stays where it flies (a lost navigator: where its successor
/// will fly once the loss is known, a timeout later; METHOD §3).
#[inline(always)]
fn coast(
    params: &ControllerParams,
    tracks: &impl Tracks,
    navigator: Option<UavId>,
    s: usize,
    now_s: f64,
) -> Option<(UavId, f64)> {
    let on_plan = tracks.carries();
    let longest = if on_plan { params.coast_s.max(params.track_timeout_s) } else { params.coast_s };
    let id = tracks.coasting(s, now_s, longest, relay_max_age_s(params, tracks))?;
    let missing = tracks.missing(s, now_s);
    let within = |max_s: f64| missing <= max_s + crate::predictor::SAME_INSTANT_S;
    if on_plan && Some(id) == navigator {
        return within(params.track_timeout_s).then_some((id, 1.0));
    }
    within(params.coast_s).then(|| (id, params.coasting_weight(missing)))
}

/// What a UAV whose tracks are `tracks` forwards of `navigator` at `now`
/// (`radio.relay_navigator`): its track's filtered state at its last measurement (in the
/// tracks' frame) and that measurement's age (s); None when the navigator is not tracked (heard
/// within the track timeout, measured within [`relay_max_age_s`]). What every engine's relays
/// carry ([`ProximityController::navigator_report`] for the reference's agents).
pub fn navigator_track(
    params: &ControllerParams,
    tracks: &impl Tracks,
    navigator: UavId,
    now: f64,
) -> Option<(State9, f64)> {
    tracks.report(navigator, now, relay_max_age_s(params, tracks))
}

/// How old what a UAV forwards of the navigator may be (s): `relay_max_age_s` where the plan
/// brings old reports forward, the track timeout otherwise.
fn relay_max_age_s(params: &ControllerParams, tracks: &impl Tracks) -> f64 {
    if tracks.carries() {
        params.relay_max_age_s
    } else {
        params.track_timeout_s
    }
}

/// With relative sensing, whether radio report `o` is left out: its neighbour was last heard by
/// the UAV's own sensors within `coast_s`, so its track is in the UAV's own frame (onboard
/// observations are placed in the world with the UAV's own measured state) while the report is
/// in its sender's (the sender's own measured state): mixed in, it would move the neighbour by
/// the two position fixes' difference. The track coasts over the missed detection instead.
/// With `radio_fallback`, every radio report is left out while the UAV hears anyone onboard
/// (with independent 3 m σ biases the fixes differ by ~4 m): the radio then counts only for a
/// UAV that perceives nobody onboard, whose frame it then is.
#[inline]
fn out_of_frame(
    params: &ControllerParams,
    tracks: &impl Tracks,
    o: &Observation,
    observations: &[Observation],
    now_s: f64,
) -> bool {
    params.relative_sensing
        && o.source == ObservationSource::Radio
        && (tracks.heard_onboard(o.id, now_s, params.coast_s)
            || params.radio_fallback
                && (observations.iter().any(|p| p.source == ObservationSource::Onboard)
                    || tracks.any_heard_onboard(now_s, params.coast_s)))
}

/// Step 4: `O_i − X_hold` with `O_i = (1 − λ)·X̄_i + λ·X̂ᴰ_i` (O_i = X̄_i when no main reference
/// is perceived, X̂ᴰ_i when only main references are), moved away from neighbours that come
/// too close (separation keeping, beyond the paper), and with the velocity part of W closing
/// the remaining position gap over τ (paper §2.3), never faster than braking at `stopping`
/// (m/s²) can stop within the gap: `min(|e|/τ, √(2·a·|e|))` per axis (beyond the paper; it
/// binds only on gaps wider than 2·a·τ², metres, never in formation). Also returns where the
/// centre's position is, from X_hold.
fn envelope_centre(params: &ControllerParams, est: &Estimates, stopping: Option<f64>) -> (State9, [f64; 3]) {
    let x_bar = if est.n_bar > 0 { est.sum_bar / est.w_bar } else { est.sum_dep / est.c_sum };
    let x_hat_d = (est.main_refs > 0).then(|| est.sum_dep / est.c_sum);
    centre_from(params, &x_bar, x_hat_d.as_ref(), &est.push, stopping)
}

/// Step 4 from the averages: `O_i − X_hold` from `X̄_i − X_hold` and, when main references are
/// perceived, `X̂ᴰ_i − X_hold`: `O_i = (1 − λ)·X̄_i + λ·X̂ᴰ_i`, moved by the separation `push`,
/// with the velocity part closing the remaining position gap over τ, never faster than
/// braking at `stopping` (m/s²) can stop within it; and where the centre's position is. The
/// controller's step 4 on its own sums; shared with engines that keep their sums in their own
/// form.
pub fn centre_from(
    params: &ControllerParams,
    x_bar: &State9,
    x_hat_d: Option<&State9>,
    push: &[f64; 3],
    stopping: Option<f64>,
) -> (State9, [f64; 3]) {
    let lambda = params.lambda;
    let mut o_i = match x_hat_d {
        Some(x_hat_d) => (1.0 - lambda) * x_bar + lambda * x_hat_d,
        None => *x_bar,
    };
    for k in X..VX {
        o_i[k] += push[k];
    }
    // Where the centre is (its position part may below become a velocity's step).
    let goal = [o_i[X], o_i[X + 1], o_i[X + 2]];
    if let Some(tau) = params.closing_time_s {
        for k in X..VX {
            let e = o_i[k];
            match stopping {
                Some(a) if e.abs() > 2.0 * a * tau * tau => {
                    // Far from the slot: fly the velocity that arrives without overshooting
                    // (the position part becomes that velocity's own step, so that the input
                    // follows the velocity, not a gap it cannot close in one update).
                    o_i[k + 3] += e.signum() * (2.0 * a * e.abs()).sqrt();
                    o_i[k] = 0.5 * params.dt_s * o_i[k + 3];
                }
                _ => o_i[k + 3] += e / tau,
            }
        }
    }
    (o_i, goal)
}

/// Neighbour `o`'s state as its track has it at its last measurement (the one just fed, when
/// the predictor keeps tracks, measured within `max_age_s`; the raw observation otherwise) and
/// the time from then to its prediction one period ahead, `times` = (now, the period,
/// `max_age_s`); only when `needed` (a zero state otherwise).
#[inline]
fn seen_now(tracks: &impl Tracks, o: &Observation, times: (f64, f64, f64), needed: bool) -> (State9, f64) {
    let (now_s, dt, max_age_s) = times;
    if !needed {
        return (State9::zeros(), dt);
    }
    match tracks.report(o.id, now_s, max_age_s) {
        Some((x, age)) => (x, dt + age),
        None => (o.state, dt + o.age_s),
    }
}

/// How the formation and the vehicle move, for [`implied_deviation`].
struct Motion<'a> {
    /// The vehicle whose turn rate ([`VehicleModel::turn_rate`]) turns the formation as one
    /// rigid body (`turn_feedforward`); None: no turn feed-forward.
    turn: Option<&'a VehicleModel>,
    /// The vehicle's setpoint lead (s, [`VehicleModel::setpoint_lag_s`]).
    lead_s: f64,
    /// The formation's turn acceleration ω̇ (rad/s², [`TurnTrend`]).
    omega_dot: f64,
    /// The formation's turn rate when the navigator is perceived (rad/s): every W turns at it.
    omega: Option<f64>,
    /// Δt (s).
    dt: f64,
}

impl Motion<'_> {
    /// True when a neighbour's state now is needed beside its prediction.
    fn needs_now(&self) -> bool {
        self.turn.is_some() || self.lead_s > 0.0
    }
}

/// `X̂_ij − X_hold` for neighbour `id` predicted at `f_x_j` (eq. 10, attitudes wrapped) and
/// seen at `seen.0` a time `seen.1` before that prediction, and the turn rate W turned at;
/// None when the neighbour is not in the formation. In a formation that turns as one body, W
/// turns at the reference's turn rate (from the two states). For a vehicle whose velocity lags
/// its setpoint by τ ([`VehicleModel::setpoint_lag_s`], the multirotor's velocity loop), the
/// velocity part is that of the slot τ later: the slot's acceleration (j's, from its two
/// velocities, plus the centripetal `ω × (ω × r)` and tangential `ω̇ × r` of the turn) times
/// τ, so that a ramp of velocity is followed without the loop's lag (METHOD §5, the
/// multirotor).
#[inline]
fn implied_deviation(
    formation: &Formation,
    motion: &Motion<'_>,
    id: UavId,
    seen: (&State9, f64),
    f_x_j: &State9,
    slot_i: &FormationSlot,
    x_hold: &State9,
) -> Option<(State9, Option<f64>)> {
    let slot_j = formation.slot(id)?;
    let (x_j, span) = (seen.0, seen.1.max(motion.dt));
    // X̂_ij − X_hold = (F·X_j + W_ij) − X_hold, built in place.
    let mut delta = f_x_j - x_hold;
    let omega = motion.turn.map(|v| motion.omega.unwrap_or_else(|| v.turn_rate(x_j, f_x_j, span)));
    formation.add_w_with(omega, slot_i, slot_j, f_x_j, &mut delta);
    if motion.lead_s > 0.0 {
        let (tau, dt, w, w_dot) = (motion.lead_s, span, omega.unwrap_or(0.0), motion.omega_dot);
        // r = R_f(d_i − d_j), W's horizontal position part.
        let r = [delta[X] - (f_x_j[X] - x_hold[X]), delta[X + 1] - (f_x_j[X + 1] - x_hold[X + 1])];
        // The turn's centripetal −ω²·r and tangential ω̇ × r.
        let turn = [-w * w * r[0] - w_dot * r[1], -w * w * r[1] + w_dot * r[0], 0.0];
        for k in 0..3 {
            let a_j = (f_x_j[VX + k] - x_j[VX + k]) / dt;
            delta[VX + k] += tau * (a_j + turn[k]);
        }
    }
    for k in state::ALPHA..=state::GAMMA {
        delta[k] = crate::angle::wrap_pi(delta[k]);
    }
    Some((delta, omega))
}

/// Adds to `push` how far the UAV, at `x_hold` next step, must move away from neighbour `id`
/// predicted at `x_j` to be `separation` m from it, when it is closer than that and closer than
/// [`SEPARATION_SLOT_FRACTION`] of their slots' distance.
#[inline]
fn keep_apart(
    formation: &Formation,
    id: UavId,
    x_j: &State9,
    slot_i: &FormationSlot,
    x_hold: &State9,
    separation: f64,
    push: &mut [f64; 3],
) {
    let p = [x_hold[X] - x_j[X], x_hold[X + 1] - x_j[X + 1], x_hold[X + 2] - x_j[X + 2]];
    push_apart(p, separation, || formation.slot(id).map(|s| (s.offset_m - slot_i.offset_m).norm()), push);
}

/// Separation keeping from `p = X_hold − X_j` (positions, m): adds to `push` how far to move
/// to be `separation` m from the neighbour, when closer than that and closer than
/// [`SEPARATION_SLOT_FRACTION`] of their slots' distance (`slots_m`, asked only then; None: not
/// in the formation).
#[inline]
pub fn push_apart(p: [f64; 3], separation: f64, slots_m: impl FnOnce() -> Option<f64>, push: &mut [f64; 3]) {
    let d2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    if d2 >= separation * separation {
        return;
    }
    let Some(slots_m) = slots_m() else { return };
    let limit = separation.min(SEPARATION_SLOT_FRACTION * slots_m);
    let d = d2.sqrt();
    if d < limit && d > 1e-9 {
        for k in 0..3 {
            push[k] += (limit - d) * p[k] / d;
        }
    }
}

#[cfg(test)]
mod few_ids_tests {
    use super::*;

    #[test]
    fn the_few_ids_count_as_a_set_does() {
        // Ids that share their home slot, neighbours' ids, 0 and the free slot's own id, in a
        // scrambled order with repeats, up to SCAN_UP_TO different ones.
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        for round in 0..200 {
            let mut few = FewIds::new();
            let mut set = std::collections::HashSet::new();
            let pool: Vec<u32> = (0..SCAN_UP_TO as u32)
                .map(|k| match (k + round) % 5 {
                    0 => k * 64,
                    1 => 1000 + k,
                    2 => FREE_ID - k,
                    3 => k << 26,
                    _ => k,
                })
                .collect();
            for _ in 0..64 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let id = pool[(state % pool.len() as u64) as usize];
                assert_eq!(few.contains(id), set.contains(&id), "{id}");
                assert_eq!(few.insert(id), set.insert(id), "{id}");
                assert!(few.contains(id));
            }
        }
    }
}
