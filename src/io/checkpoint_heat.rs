//! The heat in flight in a checkpoint (issues 20 and 21): what the
//! mechanics handed to the thermal system for the next step and that step
//! has not yet released, the frictional heat and the free spheres' faces'
//! heat (one vector, `ThermalSystem::add_heat`), per node by global id in
//! `state/pending_heat` (J; the copies of a node sharing a row split it,
//! `ThermalSystem::pending_heat`). A repartition carries the same rows
//! through memory (`run::checkpoint::Snapshot`), so a restart and a
//! repartition put it back by one path. Checkpoints from before it lack
//! the dataset: they continue with nothing pending. Also the readers of the
//! heat account's saved scalars.

use super::checkpoint::CheckpointFile;

/// The node dataset of the heat handed over and not yet released.
pub const PENDING_HEAT: &str = "state/pending_heat";

/// The heat account of the scalars (radiation and friction are 0 in
/// checkpoints from before them).
pub(super) fn heat_of(sc: &[f64]) -> [f64; 7] {
    let extra = |i: usize| sc.get(i).copied().unwrap_or(0.0);
    [sc[3], sc[4], sc[5], sc[6], sc[7], extra(11), extra(12)]
}

/// The saved account base: 7 values, or 5 or 6 from before radiation and
/// frictional heating (then 0).
pub(super) fn account_base(v: &[f64]) -> Option<[f64; 7]> {
    match v.len() {
        5..=7 => {
            let mut b = [0.0; 7];
            b[..v.len()].copy_from_slice(v);
            Some(b)
        }
        _ => None,
    }
}

impl CheckpointFile {
    /// Whether the checkpoint holds the dataset `name`.
    pub fn holds(&self, name: &str) -> bool {
        self.file.link_exists(name)
    }
}
