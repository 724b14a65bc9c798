//! The joints' histories carried through a repartition (issue 19): the
//! damage, slip and breaking time of every joint leave with the old
//! parts in blocks of global joint numbers over the ranks (the rows a
//! checkpoint's `state/joints` holds) and are read back by the ranks
//! that hold the joints afterwards, as a restart reads them from the file;
//! then the thermal rows split at the broken joints again. Nothing of the
//! size of all the joints is on any rank: each holds its block.
//!
//! Collective: every rank calls these at the same repartition.

use mpi::topology::SimpleCommunicator;

use crate::fracture::set::SAVED_JOINT;
use crate::model::Model;
use crate::parallel::exchange::{from_blocks, to_blocks};
use crate::parallel::Part;

use super::Mechanics;

/// Every joint's history in blocks of global joint numbers.
pub(super) struct JointSnapshot {
    /// Number of joints of the model.
    total: u64,
    /// This rank's first joint number and its block of rows.
    lo: u64,
    rows: Vec<f64>,
}

impl JointSnapshot {
    /// Collective. The histories of the joints each rank owns, moved into
    /// blocks; `None` (on every rank) when the model has no joints.
    pub fn take(
        comm: &SimpleCommunicator,
        model: &Model,
        mech: &Mechanics,
    ) -> Option<JointSnapshot> {
        let total = model.joint_offsets().1;
        if total == 0 {
            return None;
        }
        let (ids, values) = mech.domain.saved_joints();
        let (lo, rows) = to_blocks(comm, &ids, &values, SAVED_JOINT, total);
        Some(JointSnapshot { total, lo, rows })
    }

    /// Collective. Put the histories into the new parts' joints, as a
    /// restart does: cracks become boundary faces, and the thermal rows of
    /// `part` are numbered again without the broken joints.
    pub fn restore(
        &self,
        comm: &SimpleCommunicator,
        model: &Model,
        part: &mut Part,
        mech: &mut Mechanics,
    ) {
        let ids = mech.domain.joint_gids();
        let flat = from_blocks(comm, (self.lo, &self.rows), SAVED_JOINT, self.total, &ids);
        let rows: Vec<[f64; SAVED_JOINT]> = flat
            .chunks_exact(SAVED_JOINT)
            .map(|c| std::array::from_fn(|k| c[k]))
            .collect();
        mech.domain.restore_joints(&rows);
        let broken = mech.domain.take_broken_joints();
        part.renumber_rows(comm, model, &broken);
        mech.domain.renumber_rows(part);
    }
}
