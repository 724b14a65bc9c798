//! Per-rank explicit dynamics: the subdomain of one rank (its METIS
//! elements, owned nodes and ghost nodes), halo exchange each substep, and
//! penalty-contact candidate lists (seed 004 sec 2 for the element
//! kinematics and stress; seed 000 sec 3.4 for the place of the mechanics
//! in the step; the contact potential in `contact::penalty`). The twin of
//! the thermal integrator [`crate::thermal::ThermalSystem`]; on one rank
//! it is the serial solver. The element and node kernels it calls
//! (seed 004 eqs 1–35, central differences) are in
//! [`crate::mechanics::explicit`]; ownership, halos and collectives in
//! [`crate::parallel`].
//!
//! One substep (collective over neighbours, one small all-reduce):
//! 1. contact forces of this rank's candidate pairs (they may touch ghost
//!    nodes), internal forces of the elements next to the halo;
//! 2. ghost forces sent to their owners (non-blocking) while the interior
//!    elements' forces are computed; owners add what they receive;
//! 3. owners advance their nodes (central differences);
//! 4. new positions and velocities copied to the ghosts;
//! 5. one all-reduce agrees on errors and on whether any node moved far
//!    enough (half the search margin) to redo contact detection.
//!
//! Local numbering: owned nodes first, in the part's (PETSc) order, then
//! the ghosts of the owned elements, then the ghosts that only contacts
//! need. A contact pair joins two boundary tets of different bodies and is
//! found by the rank owning one of them, `a` (the free body's tet against
//! a held body, else the lower body's), so every pair is counted once over
//! the ranks (a jointed body's pair with itself, from its lower tet, on
//! the rank that owns that tet: `self_contact`); the found pairs are then shared out so every rank has about
//! the same contact work (`balance_pairs`). With `free_damping`, step 3
//! first agrees (one all-reduce over the bodies) on which bodies touch.
//!
//! Files, one job each (all `impl ExplicitDomain`):
//! - `domain`: the domain state and its set-up ([`ExplicitDomain::new`]),
//!   nodal temperatures;
//! - `time_step`: the explicit step from the bodies' highest frequencies
//!   and the contact penalty;
//! - `substep`: [`ExplicitDomain::advance`], one substep (contact and
//!   element forces, halo exchange, central differences);
//! - `candidates`: contact detection (the one contact search, the ghost
//!   list and halo) and the thermal narrow phase on the candidates in a
//!   coupled run (`thermal_contacts`);
//! - `pair_balance`: `balance_pairs`, the pair work shared over the
//!   ranks, a pair going back within a step to the rank that evaluated it;
//! - `carry`: what a touching pair keeps across a detection (its
//!   linearised overlap, its touch mark), and the candidates' key order;
//! - `handover`: per-pair records (those models, the friction springs)
//!   handed to whichever rank evaluates the pair after a detection;
//! - `force_sum`: the global-order force summation that makes the
//!   trajectories bitwise the same on any number of ranks (the elements'
//!   fixed slots);
//! - `pair_sum`: the touching pairs' share of it, routed each substep to
//!   the nodes' owners with their keys;
//! - `state`: energies, output fields, checkpoint save and restore;
//! - `self_contact`: which jointed bodies search themselves, and which of
//!   their tets shared a vertex (those never pair);
//! - `joints`: the cohesive joints of the jointed bodies (issue 19),
//!   whose forces are added to the owned nodes after the force sum, the
//!   crack faces they leave, and their rows of the joint output;
//! - `particles`: the bonded particles of bodies with an element set made
//!   particles (issue 21), their links to the elements, advanced after
//!   the force sum, and their rows of the particle output.
//! - `spheres`: the free discrete-element spheres of this rank's slab
//!   (issue 21, beyond the papers), their ghosts and migrants, their
//!   contacts with each other and the bodies' boundary triangles, whose
//!   shares are added to the owned nodes after the force sum.

mod balance;
mod candidates;
mod carry;
mod domain;
mod force_sum;
mod gaps;
mod handover;
mod hexes;
mod joints;
mod pair_balance;
mod pair_sum;
mod particles;
mod self_contact;
mod spheres;
mod springs;
mod state;
mod substep;
mod time_step;

#[cfg(test)]
mod tests;

pub use balance::BodyLoad;
pub use domain::ExplicitDomain;
pub use joints::{merge_body_cracks, JointRows};
pub use particles::ParticleRows;
pub use spheres::SphereRows;
pub use state::{
    MechanicsCounters, MechanicsState, SavedMotion, SphereHeat, TakenSpheres, DETECT_PHASES,
    SUBSTEP_PHASES,
};

/// Marks an absent local index or slot.
const NONE: u32 = u32::MAX;
