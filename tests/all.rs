//! All the integration tests in one binary: one build and one link, and
//! one pool of test threads over every test (no binary waits for its
//! longest test while a core idles). Each module is a file of this
//! directory; `cargo test --test all fracture::` runs one of them.

mod common;

mod ambient;
mod bad_input;
mod brazilian;
mod cli;
mod contact;
mod contact_surface;
mod crack_contact;
mod fede_expansion;
mod fede_heat_run;
mod fede_kernels;
mod fede_run;
mod fracture;
mod free_spheres;
mod free_spheres_heat;
mod free_spheres_run;
mod friction_stick;
mod fuzz;
mod hex8_run;
mod joint_rebalance;
mod joint_set_split;
mod joint_split;
mod joint_split_thermal;
mod many_ranks;
mod mechanics;
mod packing;
mod packing_cracking;
mod particle_restart;
mod particle_split;
mod self_contact;
mod slab;
mod thermal_contact;
mod thermal_cracking;
mod two_rank;
