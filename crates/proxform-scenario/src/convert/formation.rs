//! `[formation]`: slots (explicit or a generated shape), the frame, and dependency tables.

use std::collections::BTreeMap;
use std::sync::Arc;

use nalgebra::Vector3;
use proxform_core::angle::deg;
use proxform_core::{
    DependencySet, Formation, FormationFrame, FormationSchedule, FormationSlot, FormationStage, UavId,
};

use super::values::{
    distance, distance3, err, finite, positive, probability, required, show, uav, vec3, SpecError, MAX_DISTANCE_M,
};
use super::MAX_UAVS;
use crate::defaults;
use crate::formation::lattice::default_levels;
use crate::formation::shapes::Shape;
use crate::spec::{FormationSpec, ShapeSpec};

/// A slot's `depends_on` table as written: UAV number → degree.
pub type ExplicitRefs = BTreeMap<String, f64>;

/// The formation as written: slots, frame, and each slot's explicit `depends_on` table.
pub struct Slots {
    /// One slot per UAV.
    pub slots: Vec<FormationSlot>,
    /// The formation frame.
    pub frame: FormationFrame,
    /// Each slot's `depends_on`, if written.
    pub explicit: Vec<Option<ExplicitRefs>>,
}

/// The formation's slots, its frame, and each slot's explicit `depends_on` table; a shape's
/// defaults keep its UAVs `safety_distance_m` apart (a lattice's levels).
pub fn slots(f: &FormationSpec, safety_distance_m: f64) -> Result<Slots, SpecError> {
    let frame = match f.frame.as_deref() {
        None | Some("world") => FormationFrame::World,
        Some("course") => FormationFrame::Course,
        Some("heading") => FormationFrame::Heading,
        Some(other) => {
            return Err(err(
                "formation.frame",
                format!("unknown frame \"{other}\" (expected \"world\", \"course\" or \"heading\")"),
            ))
        }
    };
    let (slots, explicit) = slots_of(f, safety_distance_m)?;
    let n = slots.len();
    if n < 2 {
        return Err(err("formation", format!("needs at least 2 UAVs, found {n}")));
    }
    Ok(Slots { slots, frame, explicit })
}

type SlotsAndRefs = (Vec<FormationSlot>, Vec<Option<ExplicitRefs>>);

fn slots_of(f: &FormationSpec, safety_distance_m: f64) -> Result<SlotsAndRefs, SpecError> {
    match (&f.shape, f.slot.is_empty()) {
        (Some(_), false) => {
            Err(err("formation", "give either [[formation.slot]] entries or a [formation.shape], not both"))
        }
        (None, true) => Err(err("formation", "needs [[formation.slot]] entries or a [formation.shape]")),
        (Some(shape), true) => {
            let slots = shape_of(shape, safety_distance_m)?.slots();
            // A shape of many UAVs at a large spacing can span more than the models mean.
            if let Some(far) =
                slots.iter().map(|s| s.offset_m.amax()).max_by(f64::total_cmp).filter(|d| *d > MAX_DISTANCE_M)
            {
                return Err(err(
                    "formation.shape.spacing_m",
                    format!(
                        "the shape reaches {} m from UAV 1, beyond ±{} m: the models are for formations and flights of \
                         up to 1000 km",
                        super::values::show(far),
                        super::values::show(MAX_DISTANCE_M)
                    ),
                ));
            }
            let n = slots.len();
            Ok((slots, vec![None; n]))
        }
        (None, false) => {
            let n = f.slot.len();
            let mut slots = vec![None; n];
            let mut deps = vec![None; n];
            for (k, s) in f.slot.iter().enumerate() {
                let key = format!("formation.slot[{}]", k + 1);
                let id = required(&format!("{key}.id"), s.id)?;
                if id == 0 || id as usize > n {
                    return Err(err(
                        format!("{key}.id"),
                        format!("UAV numbers run from 1 to {n} (the number of slots), found {id}"),
                    ));
                }
                let i = id as usize - 1;
                if slots[i].is_some() {
                    return Err(err(format!("{key}.id"), format!("duplicate id {id}")));
                }
                let offset = distance3(&format!("{key}.offset_m"), required(&format!("{key}.offset_m"), s.offset_m)?)?;
                let att = match s.attitude_offset_deg {
                    Some(a) => vec3(&format!("{key}.attitude_offset_deg"), a)?.map(deg),
                    None => Vector3::zeros(),
                };
                slots[i] = Some(FormationSlot { offset_m: offset, attitude_offset_rad: att });
                deps[i] = s.depends_on.clone();
            }
            let slots = slots.into_iter().map(|s| s.unwrap_or(FormationSlot::at(0.0, 0.0, 0.0))).collect();
            Ok((slots, deps))
        }
    }
}

fn shape_of(s: &ShapeSpec, safety_distance_m: f64) -> Result<Shape, SpecError> {
    let kind = required("formation.shape.kind", s.kind.clone())?;
    let uavs = || -> Result<usize, SpecError> {
        let n = required("formation.shape.uavs", s.uavs)? as usize;
        if !(2..=MAX_UAVS).contains(&n) {
            return Err(err("formation.shape.uavs", format!("needs 2 to {MAX_UAVS} UAVs, found {n}")));
        }
        Ok(n)
    };
    let spacing = || {
        let v = positive("formation.shape.spacing_m", required("formation.shape.spacing_m", s.spacing_m)?)?;
        distance("formation.shape.spacing_m", v)
    };
    let angle = || -> Result<f64, SpecError> {
        let a = finite("formation.shape.angle_deg", s.angle_deg.unwrap_or(defaults::SHAPE_ANGLE_DEG))?;
        if a <= 0.0 || a >= 90.0 {
            return Err(err("formation.shape.angle_deg", format!("must be in (0, 90), found {a}")));
        }
        Ok(deg(a))
    };
    let level = || {
        distance("formation.shape.level_step_m", finite("formation.shape.level_step_m", s.level_step_m.unwrap_or(0.0))?)
    };
    Ok(match kind.as_str() {
        "triangle" => {
            let rows = required("formation.shape.rows", s.rows)? as usize;
            if !(2..=4000).contains(&rows) {
                return Err(err("formation.shape.rows", format!("needs 2 to 4000 rows, found {rows}")));
            }
            Shape::Triangle { rows, spacing: spacing()?, level_step: level()? }
        }
        "v" => Shape::V { uavs: uavs()?, spacing: spacing()?, angle: angle()?, level_step: level()? },
        "echelon" => {
            let left = match s.side.as_deref() {
                None | Some("right") => false,
                Some("left") => true,
                Some(o) => return Err(err("formation.shape.side", format!("unknown side \"{o}\" (expected \"left\" or \"right\")"))),
            };
            Shape::Echelon { uavs: uavs()?, spacing: spacing()?, angle: angle()?, left, level_step: level()? }
        }
        "line_abreast" => Shape::LineAbreast { uavs: uavs()?, spacing: spacing()?, level_step: level()? },
        "column" => Shape::Column { uavs: uavs()?, spacing: spacing()?, level_step: level()? },
        "diamond" => Shape::Diamond { uavs: uavs()?, spacing: spacing()? },
        "grid" => Shape::Grid { uavs: uavs()?, spacing: spacing()? },
        "circle" => Shape::Circle { uavs: uavs()?, radius: spacing()? },
        "lattice" => {
            let n = uavs()?;
            let levels = match s.levels {
                Some(0) => return Err(err("formation.shape.levels", "must be ≥ 1")),
                Some(l) => l as usize,
                None => default_levels(n),
            };
            // Levels on top of each other need a step between them: the built-in swarm's by
            // default, or twice the safety distance where that is more (a lattice of one level
            // has none).
            let level_step = match s.level_step_m {
                None if levels > 1 => -default_level_step_m(safety_distance_m),
                _ => level()?,
            };
            if levels > 1 && level_step == 0.0 {
                return Err(err(
                    "formation.shape.level_step_m",
                    format!("{levels} levels need a height step between them (found 0 m)"),
                ));
            }
            Shape::Lattice { uavs: n, spacing: spacing()?, levels, level_step }
        }
        other => {
            return Err(err(
                "formation.shape.kind",
                format!("unknown shape \"{other}\" (expected triangle, v, echelon, line_abreast, column, diamond, grid, lattice or circle)"),
            ))
        }
    })
}

/// A lattice's height between levels when the file gives none (m): the built-in swarm's,
/// or twice the safety distance where that is more (its levels stand on top of each other).
pub fn default_level_step_m(safety_distance_m: f64) -> f64 {
    crate::formation::lattice::LEVEL_M.max(2.0 * safety_distance_m)
}

/// Every UAV's dependency table: its explicit `depends_on`, or one derived from the geometry
/// (`[formation.dependencies]`, METHOD §6 Choice).
pub fn dependencies(
    f: &FormationSpec,
    slots: &[FormationSlot],
    explicit: &[Option<ExplicitRefs>],
    navigator: UavId,
    sensing_range_m: f64,
) -> Result<Vec<DependencySet>, SpecError> {
    let n = slots.len();
    let auto = f.dependencies.clone().unwrap_or_default();
    let k = auto.k.unwrap_or(defaults::REFERENCES_PER_UAV) as usize;
    if k == 0 {
        return Err(err("formation.dependencies.k", "must be ≥ 1"));
    }
    let max_d = match auto.max_distance_m {
        Some(v) => positive("formation.dependencies.max_distance_m", v)?,
        None => sensing_range_m,
    };
    let nav_degree = match auto.navigator_degree {
        Some(v) => {
            let v = probability("formation.dependencies.navigator_degree", v)?;
            if v >= 1.0 {
                return Err(err("formation.dependencies.navigator_degree", "must be below 1"));
            }
            v
        }
        None => 0.0,
    };
    let derived = crate::formation::autodeps::derive(slots, navigator, k, max_d, nav_degree)
        .map_err(|e| err("formation.dependencies", e.to_string()))?;
    (0..n)
        .map(|i| match &explicit[i] {
            Some(refs) => {
                let key = format!("formation.slot[{}].depends_on", i + 1);
                let mut out = Vec::new();
                for (id, degree) in refs {
                    let j: u32 = id.parse().map_err(|_| err(&key, format!("\"{id}\" is not a UAV number")))?;
                    let j = uav(&key, j, n)?;
                    if j.index() == i {
                        return Err(err(&key, format!("UAV {} cannot depend on itself", i + 1)));
                    }
                    let d = finite(&key, *degree)?;
                    if d <= 0.0 {
                        return Err(err(&key, format!("degree of UAV {id} must be > 0, found {d}")));
                    }
                    out.push((j, d));
                }
                DependencySet::new(UavId(i as u32), n, out).map_err(|e| err(&key, e.to_string()))
            }
            None => Ok(derived[i].clone()),
        })
        .collect()
}

/// Whether some slot lies farther from the navigator's than `sensing_range_m` (the navigator's
/// own view cannot reach it in formation).
pub fn beyond_sensing_of_navigator(slots: &[FormationSlot], navigator: UavId, sensing_range_m: f64) -> bool {
    let Some(nav) = slots.get(navigator.index()) else { return false };
    slots.iter().any(|s| (s.offset_m - nav.offset_m).norm() > sensing_range_m)
}

/// A warning naming the followers the navigator's state cannot reach: slots beyond both the
/// radio's range and the sensing range of the navigator's slot, or, when every UAV relays
/// (`relay_navigator`), of every slot the navigator's state reaches hop by hop. With
/// `navigator_degree` they lean on their other references only.
pub fn beyond_the_navigators_radio(
    slots: &[FormationSlot],
    navigator: UavId,
    radio_range_m: f64,
    sensing_range_m: f64,
    relay: bool,
) -> Option<SpecError> {
    let reach = radio_range_m.max(sensing_range_m);
    if !reach.is_finite() || slots.get(navigator.index()).is_none() {
        return None;
    }
    let at = |i: usize| [slots[i].offset_m.x, slots[i].offset_m.y, slots[i].offset_m.z];
    let mut reached = vec![false; slots.len()];
    reached[navigator.index()] = true;
    let mut grid = proxform_core::grid::NeighbourGrid::new();
    grid.rebuild((0..slots.len()).map(at), reach);
    let mut queue = vec![navigator.index()];
    while let Some(i) = queue.pop() {
        grid.for_each_within(at(i), reach, |j, _, _| {
            let j = j as usize;
            if !reached[j] && (relay || i == navigator.index()) {
                reached[j] = true;
                queue.push(j);
            }
        });
    }
    let far: Vec<usize> = (0..slots.len()).filter(|&i| !reached[i]).collect();
    if far.is_empty() {
        return None;
    }
    let shown: Vec<String> = far.iter().take(8).map(|i| (i + 1).to_string()).collect();
    let more = if far.len() > 8 { format!(" and {} more", far.len() - 8) } else { String::new() };
    Some(err(
        "formation.dependencies.navigator_degree",
        format!(
            "UAV{} {}{more} fly beyond the reach of the navigator's radio ({} m) and sensing range{}: they cannot \
             hear it and lean on their other references only{}",
            if far.len() > 1 { "s" } else { "" },
            shown.join(", "),
            super::values::show(radio_range_m),
            if relay { ", even relayed" } else { "" },
            if relay { "" } else { " (radio.relay_navigator = true forwards it hop by hop)" }
        ),
    ))
}

/// Warnings for UAVs whose main references never lead, however far followed, to the navigator:
/// they lean only on each other (or on nobody) and can drift away together.
pub fn drifting_groups(deps: &[DependencySet], navigator: UavId, f: &FormationSpec) -> Vec<SpecError> {
    let n = deps.len();
    // Who leans on whom, reversed: from the navigator, follow the UAVs that name each UAV
    // reached (compressed rows: O(N·k) in time and memory).
    let mut start = vec![0u32; n + 1];
    for d in deps {
        for (j, _) in d.refs() {
            start[j.index() + 1] += 1;
        }
    }
    for k in 0..n {
        start[k + 1] += start[k];
    }
    let mut fill = start.clone();
    let mut leaners = vec![0u32; start[n] as usize];
    for (i, d) in deps.iter().enumerate() {
        for (j, _) in d.refs() {
            leaners[fill[j.index()] as usize] = i as u32;
            fill[j.index()] += 1;
        }
    }
    let mut reached = vec![false; n];
    let mut queue = vec![navigator.0];
    reached[navigator.index()] = true;
    while let Some(j) = queue.pop() {
        for &i in &leaners[start[j as usize] as usize..start[j as usize + 1] as usize] {
            if !reached[i as usize] {
                reached[i as usize] = true;
                queue.push(i);
            }
        }
    }
    let adrift: Vec<usize> = (0..n).filter(|&i| !reached[i]).collect();
    if adrift.is_empty() {
        return Vec::new();
    }
    let first = adrift[0];
    let key = if f.slot.is_empty() {
        "formation.dependencies".to_string()
    } else {
        format!("formation.slot[{}].depends_on", first + 1)
    };
    let shown: Vec<String> = adrift.iter().take(8).map(|i| (i + 1).to_string()).collect();
    let more = if adrift.len() > 8 { format!(" and {} more", adrift.len() - 8) } else { String::new() };
    vec![err(
        key,
        format!(
            "UAVs {}{more} never lean, through their main references, on the navigator (UAV {}): they can drift \
             away together; name a UAV that leads to it, or set formation.dependencies.navigator_degree",
            shown.join(", "),
            navigator.0 + 1
        ),
    )]
}

/// `[[formation.change]]`: each change's slots (explicit or a shape, in the formation's frame,
/// as many as the formation's, the safety distance apart) and dependency tables, checked like
/// the formation's; times strictly increasing (a change after the end of the flight is kept,
/// with a warning: a shortened flight stays valid).
pub fn schedule(
    f: &FormationSpec,
    first: &Formation,
    navigator: UavId,
    safety_distance_m: f64,
    duration_s: f64,
    sensing_range_m: f64,
    warnings: &mut Vec<SpecError>,
) -> Result<FormationSchedule, SpecError> {
    let mut stages = Vec::with_capacity(f.change.len());
    let mut last = 0.0;
    for (k, c) in f.change.iter().enumerate() {
        let key = format!("formation.change[{}]", k + 1);
        let at_s = positive(&format!("{key}.at_s"), required(&format!("{key}.at_s"), c.at_s)?)?;
        if at_s <= last {
            return Err(err(
                format!("{key}.at_s"),
                format!("{} s must come after the start and the change before ({} s)", show(at_s), show(last)),
            ));
        }
        if at_s >= duration_s {
            warnings.push(err(
                format!("{key}.at_s"),
                format!("comes at {} s, after the end of the flight ({} s): never flown", show(at_s), show(duration_s)),
            ));
        }
        last = at_s;
        let spec = FormationSpec {
            frame: f.frame.clone(),
            slot: c.slot.clone(),
            shape: c.shape.clone(),
            dependencies: c.dependencies.clone(),
            change: Vec::new(),
            reassign_on_loss: None,
        };
        // Errors name the change's own keys.
        let within = |e: SpecError| SpecError {
            key: e.key.strip_prefix("formation").map_or(e.key.clone(), |rest| format!("{key}{rest}")),
            message: e.message,
        };
        let Slots { slots, explicit, .. } = slots(&spec, safety_distance_m).map_err(within)?;
        if slots.len() != first.len() {
            return Err(err(
                key,
                format!("has {} slots; the formation has {} UAVs, and keeps them", slots.len(), first.len()),
            ));
        }
        super::feasibility::separated(&slots, safety_distance_m).map_err(within)?;
        let dependencies = dependencies(&spec, &slots, &explicit, navigator, sensing_range_m).map_err(within)?;
        // A change at or after the end is checked, warned of and never flown: it is not in the
        // schedule (at exactly the end, the last frame was judged against it).
        if at_s >= duration_s {
            continue;
        }
        stages.push(FormationStage {
            at_s,
            formation: Arc::new(Formation { slots, frame: first.frame }),
            dependencies,
        });
    }
    FormationSchedule::new(stages, first.len()).map_err(|e| err("formation.change", e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lattice_of_several_levels_steps_down_by_default() {
        let shape_safe = |levels: Option<u32>, step: Option<f64>, safety_m: f64| {
            let spec = ShapeSpec {
                kind: Some("lattice".into()),
                uavs: Some(100),
                spacing_m: Some(50.0),
                levels,
                level_step_m: step,
                ..ShapeSpec::default()
            };
            shape_of(&spec, safety_m)
        };
        let shape = |levels: Option<u32>, step: Option<f64>| shape_safe(levels, step, 3.0);
        // Two levels by size: 20 m apart unless the file says otherwise.
        match shape(None, None).expect("valid") {
            Shape::Lattice { levels, level_step, .. } => assert_eq!((levels, level_step), (2, -20.0)),
            other => panic!("{other:?}"),
        }
        // Or twice the safety distance where that is more (the kinematic vehicle's 50 m).
        match shape_safe(None, None, 50.0).expect("valid") {
            Shape::Lattice { levels, level_step, .. } => assert_eq!((levels, level_step), (2, -100.0)),
            other => panic!("{other:?}"),
        }
        match shape(Some(3), Some(15.0)).expect("valid") {
            Shape::Lattice { levels, level_step, .. } => assert_eq!((levels, level_step), (3, 15.0)),
            other => panic!("{other:?}"),
        }
        match shape(Some(1), None).expect("valid") {
            Shape::Lattice { level_step, .. } => assert_eq!(level_step, 0.0),
            other => panic!("{other:?}"),
        }
        let e = shape(Some(2), Some(0.0)).expect_err("levels on top of each other");
        assert_eq!(e.key, "formation.shape.level_step_m");
    }

    #[test]
    fn uavs_that_never_lead_to_the_navigator_are_named() {
        let deps = |tables: &[&[(u32, f64)]]| -> Vec<DependencySet> {
            tables
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    DependencySet::new(UavId(i as u32), tables.len(), t.iter().map(|&(j, c)| (UavId(j), c)).collect())
                        .expect("valid")
                })
                .collect()
        };
        let spec = FormationSpec::default();
        // 2 → 1, 3 → 2: everybody leads to UAV 1.
        assert!(drifting_groups(&deps(&[&[], &[(0, 1.0)], &[(1, 1.0)]]), UavId(0), &spec).is_empty());
        // 3 ↔ 4 lean only on each other; 5 leans on nobody.
        let w = drifting_groups(&deps(&[&[], &[(0, 1.0)], &[(3, 1.0)], &[(2, 1.0)], &[]]), UavId(0), &spec);
        assert_eq!(w.len(), 1);
        assert!(w[0].message.starts_with("UAVs 3, 4, 5 never lean"), "{}", w[0].message);
    }
}
