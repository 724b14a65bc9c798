//! The free spheres' heat handed to the FE (issue 21, beyond the papers):
//! the heat (J) the spheres' contacts took from (or gave to) the Tet4
//! faces' nodes over a thermal step's substeps, released into the nodes'
//! rows over the next step as a source, through the vector the
//! frictional heat uses (`ThermalSystem::add_heat`), but counted apart:
//! the FE's balance reads stored change = boundary heat + the spheres'
//! released heat, and the spheres' stored change is minus what they took
//! (`dynamics::spheres`), so the two close together.

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::ThermalSystem;
use crate::error::{Error, Result};
use crate::parallel::Part;

/// The spheres' heat in the FE's hands (J, over all ranks).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SphereSource {
    /// Handed over and not yet released.
    pub pending: f64,
    /// Released into the FE rows since the start (negative when the
    /// spheres took heat from the bodies).
    pub released: f64,
}

impl SphereSource {
    /// A step releases what is pending: returns it.
    pub(super) fn release(&mut self) -> f64 {
        let q = self.pending;
        self.released += q;
        self.pending = 0.0;
        q
    }
}

impl ThermalSystem<'_> {
    /// Collective. Hand over the heat `heat` (J, per owned node of `part`,
    /// part order) the spheres' faces gave the nodes over the last step,
    /// released over the next one. `gdt` is each node's Σ N_I g Δt (J/K):
    /// the exchange is explicit for the nodes, so it must not exceed the
    /// node's (lumped) capacity, else the node could overshoot the
    /// spheres' temperature (the maximum principle). Returns the largest
    /// ratio Σ N_I g Δt / C over the nodes.
    pub fn add_sphere_heat(
        &mut self,
        comm: &SimpleCommunicator,
        part: &Part,
        heat: &[f64],
        gdt: &[f64],
    ) -> Result<f64> {
        let capacity = super::super::node_rows::node_values(part, &self.ops.capacity_rowsum)?;
        let (mut worst, mut at) = (0.0f64, u32::MAX);
        for (l, (&g, &c)) in gdt.iter().zip(&capacity).enumerate() {
            if g > worst * c {
                (worst, at) = (g / c, part.owned_gids()[l]);
            }
        }
        let mut all = 0.0;
        comm.all_reduce_into(&worst, &mut all, SystemOperation::max());
        if all > 1.0 {
            let mine = if worst == all { at } else { u32::MAX };
            let mut node = 0u32;
            comm.all_reduce_into(&mine, &mut node, SystemOperation::min());
            return Err(Error::Mechanics(format!(
                "free spheres: node {node} exchanges {all:.3} times its heat capacity per \
                 degree with the spheres in one thermal step (Σ N g Δt / C > 1): the \
                 explicit coupling would overshoot; shorten dt (the thermal step) or raise \
                 the contact resistance"
            )));
        }
        let Some(f) = self.friction.as_mut() else {
            return Ok(all);
        };
        let before = f.sum()?;
        let rows: Vec<(u32, f64)> = part.petsc[..part.num_owned()]
            .iter()
            .zip(heat)
            .filter(|(_, &q)| q != 0.0)
            .map(|(&r, &q)| (r, q))
            .collect();
        self.add_heat(&rows)?;
        let after = self.friction.as_ref().map_or(Ok(before), |f| f.sum())?;
        self.spheres.pending += after - before;
        Ok(all)
    }

    /// The spheres' heat in the FE's hands ([`SphereSource`]).
    pub fn sphere_source(&self) -> SphereSource {
        self.spheres
    }

    /// Continue with `s` (a repartition built the system again and
    /// handed the pending heat over as [`Self::add_heat`]).
    pub fn set_sphere_source(&mut self, s: SphereSource) {
        self.spheres = s;
    }

    /// Continue with the spheres' heat `pending` (handed over, not yet
    /// released) and `released` (J) of a checkpoint, whose pending heat
    /// the restore handed over as [`Self::add_heat`].
    pub fn restore_sphere_source(&mut self, pending: f64, released: f64) {
        self.spheres = SphereSource { pending, released };
    }
}
