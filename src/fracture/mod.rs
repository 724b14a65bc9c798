//! Cohesive-zone fracture (seed 004 sec 2.7): joints inserted between the
//! tets of a body ([`insert`]), the cohesive law with damage ([`law`]) and
//! the 6-node joint element's forces ([`joint`]), the contact of a broken
//! joint's faces ([`crack`]), a rank's joints advanced
//! together with their totals ([`set`]), the continuous mesh's vertex of
//! each node copy ([`vertices`], for self-contact), the copies and joints
//! of a part numbered as the whole body's ([`numbering`]) and the jointed mesh around a part ([`part_mesh`]). Physics kernels only: no MPI, no
//! PETSc.

pub mod crack;
pub mod insert;
pub mod joint;
pub mod law;
pub mod numbering;
pub mod part_mesh;
pub mod set;
pub mod vertices;

pub use crack::{crack_forces, CrackResult, CrackState};
pub use insert::{joint_size, make_discontinuous, JointFaces, Jointed};
pub use joint::{joint_energy, joint_forces};
pub use law::{CohesiveLaw, FractureMaterial, JointState, Mode};
pub use set::{JointSet, JointTotals};
