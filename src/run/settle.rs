//! The settle criterion of a deposition: the run stops once the free
//! bodies' kinetic energy falls below a threshold (absolute, relative to
//! its peak, or an rms speed) after a given time.

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use crate::io::checkpoint::CheckpointHead;
use crate::model::Model;
use crate::parallel::Part;
use crate::scenario::SettleSpec;

use super::{Mechanics, Settled};

/// The settle criterion of a deposition: the peak kinetic energy so far,
/// and where the bodies came to rest.
pub(super) struct Settling {
    pub spec: Option<SettleSpec>,
    /// Mass of the free bodies (the settle criterion by rms speed).
    free_mass: f64,
    /// Largest kinetic energy seen (J).
    pub peak_kinetic: f64,
    pub settled: Option<Settled>,
}

impl Settling {
    /// Collective. The criterion of `model` on its parts (the free mass
    /// summed over the ranks), at a checkpoint's state on a restart.
    pub fn new(
        comm: &SimpleCommunicator,
        model: &Model,
        part: &Part,
        restart: Option<&CheckpointHead>,
    ) -> Settling {
        let m = &part.mesh;
        let mine: f64 = (0..part.num_elements())
            .filter(|&e| !model.bodies[m.body[e] as usize].is_held())
            .map(|e| model.materials[part.elem_material[e] as usize].density * m.element_volume(e))
            .sum();
        let mut free_mass = 0.0;
        comm.all_reduce_into(&mine, &mut free_mass, SystemOperation::sum());
        let spec = model.mechanics.as_ref().and_then(|m| m.settle);
        Settling {
            spec,
            free_mass,
            peak_kinetic: restart.map_or(0.0, |c| c.peak_kinetic),
            // A restart from a settled run's checkpoint is already done,
            // unless the scenario dropped the criterion: then it goes on.
            settled: restart.filter(|_| spec.is_some()).and_then(|c| {
                c.settled.map(|kinetic| Settled {
                    step: c.step,
                    time: c.time,
                    kinetic,
                })
            }),
        }
    }

    /// Collective. Whether the bodies have settled at `step`.
    pub fn check(&mut self, comm: &SimpleCommunicator, mech: &Mechanics, step: u64, dt: f64) {
        let Some(st) = self.spec else {
            return;
        };
        let ke = mech.domain.state(comm).kinetic;
        self.peak_kinetic = f64::max(self.peak_kinetic, ke);
        let peak_ke = self.peak_kinetic;
        let time = step as f64 * dt;
        // Settled when below any threshold given.
        let threshold = st
            .kinetic_energy
            .unwrap_or(0.0)
            .max(st.relative.map_or(0.0, |r| r * peak_ke))
            .max(st.rms_speed.map_or(0.0, |v| 0.5 * self.free_mass * v * v));
        if time >= st.after && peak_ke > 0.0 && ke < threshold {
            self.settled = Some(Settled {
                step,
                time,
                kinetic: ke,
            });
        }
    }
}
