//! Contact between bodies: detection (BVH broad phase over boundary tets,
//! separating-axis and clipping narrow phase), the contact surface of seed
//! 000 sec 3.1, and the contact conductance blocks of eqs 24–30.
//!
//! Pure: no MPI or PETSc. The caller picks which target tets to query (its
//! owned ones) so that every pair is found by exactly one rank.

mod detect;
pub mod penalty;
mod surface;

pub use detect::{detect_contacts, proximity_pairs, BoundaryTets, FaceList};
pub use penalty::{pair_stiffness, tet_tet_penalty, PenaltyParams, PenaltyResult};
pub use surface::{tet_tet_contact_surface, ContactSurface};

/// One contact: a boundary tet of one body overlapping a boundary tet of
/// another. `target < contactor` (element ids) so each pair has one form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPair {
    /// Target element (the lower id).
    pub target: u32,
    /// Contactor element.
    pub contactor: u32,
    /// The surface computed between them.
    pub surface: ContactSurface,
}

impl ContactPair {
    /// Seed 000 eq 25: S = (S_tar + S_con)/2.
    pub fn area(&self) -> f64 {
        self.surface.area()
    }
}

/// The contact pairs an operator is assembled with.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ContactSet {
    /// Every pair on every rank, sorted by (target, contactor).
    pub all: Vec<ContactPair>,
    /// The pairs this rank found; it inserts exactly these.
    pub local: Vec<ContactPair>,
}

impl ContactSet {
    /// Total contact area Σ S.
    pub fn total_area(&self) -> f64 {
        self.all.iter().fold(0.0, |s, p| s + p.area())
    }

    /// Whether two sets have the same pairs and the same areas to `rtol`.
    pub fn same_as(&self, other: &ContactSet, rtol: f64) -> bool {
        self.all.len() == other.all.len()
            && self.all.iter().zip(&other.all).all(|(a, b)| {
                a.target == b.target
                    && a.contactor == b.contactor
                    && (a.area() - b.area()).abs() <= rtol * a.area().max(b.area())
            })
    }
}

/// How the contact temperature drop is taken.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DeltaT {
    /// From the nodal temperatures of the two contact faces (seed 000 eq 26).
    #[default]
    Local,
    /// From the two bodies' mean temperatures (seed 000 sec 5.2).
    Average,
}

/// Seed 000 eqs 24–30, re-derived: the heat into the target is
/// q = g (w_conᵀT_con − w_tarᵀT_tar) with g = S/Rc and face-node weights w
/// (each summing to 1), given to the target nodes by w_tar and taken from
/// the contactor nodes by w_con. With v = (w_tar, −w_con) over the 8 nodes
/// (target's 4, then contactor's 4) the conductance block is g v vᵀ:
/// symmetric, positive semi-definite (rank 1), and its rows sum to zero, so
/// heat is conserved exactly. Returned row-major 8×8.
pub fn local_conductance_block(pair: &ContactPair, rc: f64) -> [f64; 64] {
    let g = pair.area() / rc;
    let mut v = [0.0; 8];
    v[..4].copy_from_slice(&pair.surface.w_target);
    for i in 0..4 {
        v[4 + i] = -pair.surface.w_contactor[i];
    }
    let mut b = [0.0; 64];
    for i in 0..8 {
        for j in 0..8 {
            // (g v_i) v_j evaluated the same way for (i, j) and (j, i).
            b[8 * i + j] = g * (v[i] * v[j]);
        }
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conductance_block_conserves_and_is_psd() {
        let surface = ContactSurface {
            s_target: 0.3,
            s_contactor: 0.5,
            w_target: [0.2, 0.3, 0.5, 0.0],
            w_contactor: [0.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
        };
        let pair = ContactPair {
            target: 1,
            contactor: 9,
            surface,
        };
        let b = local_conductance_block(&pair, 0.01);
        for i in 0..8 {
            let row: f64 = (0..8).map(|j| b[8 * i + j]).sum();
            assert!(row.abs() < 1e-12, "row {i} sums to {row}");
            for j in 0..8 {
                assert_eq!(b[8 * i + j], b[8 * j + i]);
            }
        }
        // xᵀBx = g (v·x)² ≥ 0; heat between uniform bodies at 1 and 0:
        let mut t = [0.0; 8];
        t[4..].copy_from_slice(&[1.0; 4]);
        let heat_into_target: f64 = -(0..4)
            .map(|i| (0..8).map(|j| b[8 * i + j] * t[j]).sum::<f64>())
            .sum::<f64>();
        assert!(
            (heat_into_target - 0.4 / 0.01).abs() < 1e-9,
            "{heat_into_target}"
        );
    }
}
