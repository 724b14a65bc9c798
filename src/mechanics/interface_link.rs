//! One sphere–element half bond of the FE–DE interface (issue 21, seed
//! 002 eqs 14–17 at the bond's midpoint): the sphere's half of a
//! ghost–sphere bond, whose other end is the element's material point at
//! the midpoint (velocity Σ N_I v_I there, eq 16), so velocity and force
//! are taken at one point and the coupling is work-conjugate
//! (`validation::fede_coupling` docs). The ghost's position only gives the
//! bond's direction. Pure: no MPI.

use nalgebra::Vector3;

use super::bond::{advance_bond, BondState};

/// The ends of a link in one step: the sphere's centre, velocity and
/// spin, the ghost's position and velocity, and the element's material
/// point's velocity at the midpoint.
#[derive(Debug, Clone, Copy)]
pub struct LinkEnds {
    pub sphere_x: Vector3<f64>,
    pub sphere_v: Vector3<f64>,
    pub sphere_w: Vector3<f64>,
    pub ghost_x: Vector3<f64>,
    pub ghost_v: Vector3<f64>,
    pub point_v: Vector3<f64>,
}

/// Advances the link's state over `dt` with normal and tangential
/// stiffnesses `kn`, `ks` (weight included) and the half bond's free
/// thermal elongation `free` (m, α ΔT̄ times the sphere–midpoint distance;
/// `bond::advance_bond`), and returns the force and the
/// moment on the sphere; the element's point takes −force (to be returned
/// to its nodes with N_I at the midpoint, seed 002 eq 17 there).
pub fn advance_link(
    s: &mut BondState,
    kn: f64,
    ks: f64,
    ends: &LinkEnds,
    dt: f64,
    free: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    let branch = ends.ghost_x - ends.sphere_x;
    let n = branch.normalize();
    // Moment arm at mid-step (central difference), as in bond::bond_forces.
    let half = (branch - (ends.ghost_v - ends.sphere_v) * (0.5 * dt)) * 0.5;
    // seed 002 eq 15: the sphere's velocity at the midpoint.
    let vo = ends.sphere_v + ends.sphere_w.cross(&half);
    // seed 002 eq 14: relative velocity, the element's point against the sphere's midpoint.
    let f = advance_bond(s, kn, ks, &n, &(ends.point_v - vo), dt, free);
    (f, half.cross(&f))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stretch_pulls_the_sphere_toward_the_point_and_rigid_motion_does_nothing() {
        let xs = Vector3::new(0.0, 0.0, 0.0);
        let xg = Vector3::new(2.0, 0.0, 0.0);
        let mut s = BondState::new(&xs, &xg);
        let ends = LinkEnds {
            sphere_x: xs,
            sphere_v: Vector3::new(0.3, 0.1, 0.0),
            sphere_w: Vector3::zeros(),
            ghost_x: xg,
            ghost_v: Vector3::new(0.3, 0.1, 0.0),
            point_v: Vector3::new(0.3, 0.1, 0.0),
        };
        let (f, m) = advance_link(&mut s, 10.0, 4.0, &ends, 0.1, 0.0);
        assert_eq!((f, m), (Vector3::zeros(), Vector3::zeros()));
        // The point moves away along +x: the sphere is pulled along +x with k_n d.
        let ends = LinkEnds {
            point_v: Vector3::new(1.3, 0.1, 0.0),
            ..ends
        };
        let (f, _) = advance_link(&mut s, 10.0, 4.0, &ends, 0.1, 0.0);
        assert!((f - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12, "{f:?}");
    }
}
