//! Contact between bodies: the one contact search (`search`: candidate
//! pairs and who finds them), the thermal narrow phase and contact surface
//! of seed 000 sec 3.1 (`detect`, `surface`), the search of a body's tets
//! against its own (`self_search`, self-contact of jointed bodies), the contact conductance
//! blocks of eqs 24–30, and the penalty contact (`penalty`).
//!
//! Pure: no MPI or PETSc. The caller says which tets it owns, so that
//! every pair is found by exactly one rank.

pub mod conductance;
mod detect;
pub mod gap;
pub mod penalty;
pub mod search;
pub mod self_search;
pub mod sphere;
pub mod sphere_heat;
mod surface;
pub mod table;
mod tets;

pub use detect::{
    contact_pairs, detect_contacts, tet_pair_contact, tet_shapes_contact, BoundaryTets, FaceList,
    TetFaces, THERMAL_SEARCH,
};
pub use penalty::{pair_stiffness, tet_tet_penalty, PenaltyParams, PenaltyResult};
pub use search::{finds_pair, BodyTets, Candidate, ContactSearch, SearchOptions, TetRole};
pub use surface::{tet_tet_contact_surface, ContactSurface, TetSide};
pub use tets::{ContactTets, OwnAndGhosts};

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

/// What the assembly needs of a contact pair besides its surface: the
/// PETSc numbers of its eight nodes (the target's four, then the
/// contactor's), and the two elements' materials and bodies.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PairDofs {
    /// PETSc numbers of the target's then the contactor's nodes.
    pub petsc: [u32; 8],
    /// Materials of the target and the contactor.
    pub materials: [u32; 2],
    /// Bodies of the target and the contactor.
    pub bodies: [u32; 2],
    /// Contact pressure (Pa): the penalty's normal force over the pair's
    /// surface in a run with mechanics (when a conductance needs it), else 0.
    pub pressure: f64,
    /// Mean penetration (m): the two tets' overlap volume over the pair's
    /// surface, when a conductance table depends on it, else 0.
    pub penetration: f64,
    /// Tangential slip speed (m/s) of the contactor on the target (runs
    /// with mechanics; 0 otherwise): the contact status is *sliding* above
    /// the scenario's threshold.
    pub slip: f64,
}

/// The tangential speed of tet c's mean velocity relative to tet t's
/// along t's first clipped face (`faces`: bit f, face opposite node f),
/// with `x` t's corners (0 without a clipped face).
pub fn slip_speed(x: &[[f64; 3]; 4], faces: u8, vt: &[[f64; 3]; 4], vc: &[[f64; 3]; 4]) -> f64 {
    let Some(f) = (0..4).find(|f| faces & (1 << f) != 0) else {
        return 0.0;
    };
    let (_, n, _) = gap::outward_face(x, f);
    let mut v = [0.0; 3];
    for k in 0..4 {
        for d in 0..3 {
            v[d] += 0.25 * (vc[k][d] - vt[k][d]);
        }
    }
    let vn = crate::geometry::dot(v, n);
    let t = [0, 1, 2].map(|d| v[d] - vn * n[d]);
    crate::geometry::dot(t, t).sqrt()
}

/// The mean penetration of two overlapping tets with contact surface
/// `area`: their intersection's volume over it (m).
pub fn penetration(a: &[[f64; 3]; 4], b: &[[f64; 3]; 4], area: f64) -> f64 {
    if area > 0.0 {
        crate::geometry::overlap::tet_tet_intersection(a, b).volume / area
    } else {
        0.0
    }
}

/// The contact pairs an operator is assembled with: this rank's, and the
/// totals over the ranks. No rank holds every pair.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ContactSet {
    /// The pairs this rank inserts, sorted by (target, contactor).
    pub local: Vec<ContactPair>,
    /// Per local pair, its nodes, materials and bodies.
    pub dofs: Vec<PairDofs>,
    /// Pairs over all ranks.
    pub total_pairs: u64,
    /// Contact area over all ranks, Σ S (m²).
    pub total_area: f64,
    /// This rank's near-field gap links (issue 20), in search order.
    pub gaps: Vec<gap::GapLink>,
    /// The searching faces' area linked across gaps, over all ranks (m²).
    pub total_gap_area: f64,
}

impl ContactSet {
    /// Whether this rank's pairs are those of `other`, with the same areas
    /// to `rtol` (the caller agrees over the ranks).
    pub fn same_local(&self, other: &ContactSet, rtol: f64) -> bool {
        self.local.len() == other.local.len()
            && self.gaps == other.gaps
            && self.local.iter().zip(&other.local).all(|(a, b)| {
                a.target == b.target
                    && a.contactor == b.contactor
                    && (a.area() - b.area()).abs() <= rtol * a.area().max(b.area())
            })
    }
}

/// The form of the local-ΔT contact conductance block.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactOperator {
    /// Node-to-node links ([`local_conductance_block`]): no positive
    /// off-diagonal entry, the discrete maximum principle holds.
    #[default]
    Links,
    /// The rank-one block g v vᵀ ([`rank_one_conductance_block`]): each
    /// pair's heat follows its face-averaged ΔT; positive entries between
    /// nodes of one side, so bounds can break where contact dominates
    /// conduction. Kept for the two-bar validation (seed 000 Table 2).
    RankOne,
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

/// Seed 000 eqs 24–30, re-derived as a graph Laplacian of node-to-node
/// links (issue 15).
///
/// Eq 24 gives the flux ΔT/Rc over the contact surface; eq 25 takes the
/// surface as the mean of the two sides' clipped faces, S = (S_tar +
/// S_con)/2; eq 30 couples a node only to the nodes of the other side. We
/// integrate ΔT/Rc over each side's clipped faces with that side's own
/// face-node shares (eq 24's thirds, area-weighted: S w) against the other
/// side's temperature interpolated there (its shape functions at the
/// faces' centroid, v, exact for a linear temperature), and average the
/// two sides as eq 25 does. Target node i and contactor node j are then
/// linked by the conductance
///   c_ij = (S_tar w_tar,i v_con,j + S_con v_tar,i w_con,j) / (2 Rc),
/// and the heat into target node i is Σ_j c_ij (T_j − T_i). The links sum
/// to S/Rc, so a uniform ΔT moves the same heat as eq 28; each side's
/// nodes receive their natural share of the surface (no spreading error
/// where the faces are flat, as for the two bars); and the block is the
/// Laplacian of the links: symmetric, positive semi-definite, rows summing
/// to zero (heat conserved exactly), with no positive off-diagonal entry,
/// since two nodes of the same side are not linked. With a lumped capacity
/// and backward Euler the system then stays an M-matrix and the discrete
/// maximum principle holds even where contact dominates conduction inside
/// the particles (Table 4: about 500×). (fdem first read eq 28 as the
/// rank-one block g v vᵀ with v = (w_tar, −w_con): its positive entries
/// between nodes of one side drove a packing heat-up to −126 °C.)
/// Returned row-major 8×8 over (target's 4 nodes, contactor's 4 nodes).
pub fn local_conductance_block(pair: &ContactPair, rc: f64) -> [f64; 64] {
    let s = &pair.surface;
    let (at, ac) = (s.s_target / (2.0 * rc), s.s_contactor / (2.0 * rc));
    let mut b = [0.0; 64];
    for i in 0..4 {
        for j in 0..4 {
            // Link (target i, contactor j), the same value in both triangles.
            let link =
                at * s.w_target[i] * s.v_contactor[j] + ac * s.v_target[i] * s.w_contactor[j];
            b[8 * i + 4 + j] = -link;
            b[8 * (4 + j) + i] = -link;
            b[8 * i + i] += link;
            b[8 * (4 + j) + 4 + j] += link;
        }
    }
    b
}

/// Row `a` (0..8) of [`local_conductance_block`] alone, the same values:
/// a target node's links to the contactor's nodes and their sum on the
/// diagonal, or a contactor node's (the other entries are zero).
pub fn local_conductance_row(pair: &ContactPair, rc: f64, a: usize) -> [f64; 8] {
    let s = &pair.surface;
    let (at, ac) = (s.s_target / (2.0 * rc), s.s_contactor / (2.0 * rc));
    let link = |i: usize, j: usize| {
        at * s.w_target[i] * s.v_contactor[j] + ac * s.v_target[i] * s.w_contactor[j]
    };
    let mut r = [0.0; 8];
    for k in 0..4 {
        let l = if a < 4 { link(a, k) } else { link(k, a - 4) };
        let other = if a < 4 { 4 + k } else { k };
        r[other] = -l;
        r[a] += l;
    }
    r
}

/// Row `a` (0..8) of [`rank_one_conductance_block`] alone, the same values.
pub fn rank_one_conductance_row(pair: &ContactPair, rc: f64, a: usize) -> [f64; 8] {
    let g = pair.area() / rc;
    let v = |i: usize| match i {
        0..4 => pair.surface.w_target[i],
        _ => -pair.surface.w_contactor[i - 4],
    };
    std::array::from_fn(|b| g * (v(a) * v(b)))
}

/// Seed 000 eqs 26–28 read literally: the heat g (w_conᵀT_con − w_tarᵀT_tar)
/// (g = S/Rc) enters the target's nodes by w_tar and leaves the
/// contactor's by w_con, so every node of a pair sees the pair's
/// face-averaged ΔT. With v = (w_tar, −w_con) the block is g v vᵀ:
/// symmetric, positive semi-definite, rows summing to zero, but with the
/// positive entries g w_i w_k between two nodes of one side. On the two
/// bars of seed 000 sec 4.2 (a 1D problem whose faces should carry a
/// uniform flux) it is 2–4× more accurate at late times than the links of
/// [`local_conductance_block`] (docs/validation.md).
pub fn rank_one_conductance_block(pair: &ContactPair, rc: f64) -> [f64; 64] {
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
    fn conductance_rows_are_the_blocks_rows_bitwise() {
        let surface = ContactSurface {
            s_target: 0.3,
            s_contactor: 0.25,
            w_target: [0.1, 0.2, 0.3, 0.4],
            v_target: [0.4, 0.3, 0.2, 0.1],
            w_contactor: [0.25, 0.25, 0.3, 0.2],
            v_contactor: [0.15, 0.35, 0.3, 0.2],
            ..Default::default()
        };
        let pair = ContactPair {
            target: 0,
            contactor: 1,
            surface,
        };
        let (lb, rb) = (
            local_conductance_block(&pair, 0.7),
            rank_one_conductance_block(&pair, 0.7),
        );
        for a in 0..8 {
            assert_eq!(local_conductance_row(&pair, 0.7, a), lb[8 * a..8 * a + 8]);
            assert_eq!(
                rank_one_conductance_row(&pair, 0.7, a),
                rb[8 * a..8 * a + 8]
            );
        }
    }

    #[test]
    fn conductance_block_conserves_and_is_psd() {
        let surface = ContactSurface {
            s_target: 0.3,
            s_contactor: 0.5,
            w_target: [0.2, 0.3, 0.5, 0.0],
            w_contactor: [0.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
            v_target: [0.25; 4],
            v_contactor: [0.1, 0.2, 0.3, 0.4],
            ..Default::default()
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
                if i != j {
                    assert!(b[8 * i + j] <= 0.0, "positive entry ({i}, {j})");
                }
            }
        }
        // Heat between uniform bodies at 1 and 0 is g (the same as g v vᵀ):
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

    /// A random tet near the origin with positive volume.
    fn random_tet(rng: &mut impl rand::Rng, scale: f64) -> [[f64; 3]; 4] {
        loop {
            let t: [[f64; 3]; 4] =
                std::array::from_fn(|_| std::array::from_fn(|_| scale * rng.gen_range(-1.0..1.0)));
            let v = crate::geometry::dot(
                crate::geometry::sub(t[1], t[0]),
                crate::geometry::cross(
                    crate::geometry::sub(t[2], t[0]),
                    crate::geometry::sub(t[3], t[0]),
                ),
            );
            if v.abs() > 0.05 * scale.powi(3) {
                return t;
            }
        }
    }

    #[test]
    fn random_overlapping_pairs_give_m_matrix_blocks() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(15);
        let mut tested = 0;
        while tested < 2000 {
            let a = random_tet(&mut rng, 1.0);
            let scale_b = rng.gen_range(0.2..1.5);
            let b = random_tet(&mut rng, scale_b);
            if !crate::geometry::tet_tet_overlap(&a, &b) {
                continue;
            }
            // Random subsets of boundary faces (at least one on one side).
            let fa: Vec<u8> = (0..4).filter(|_| rng.gen_bool(0.5)).collect();
            let fb: Vec<u8> = (0..4).filter(|_| rng.gen_bool(0.5)).collect();
            let nodes = |f: &[u8]| f.iter().fold(0u8, |m, &k| m | (0b1111 & !(1 << k)));
            let surface = tet_tet_contact_surface((&a, &fa, nodes(&fa)), (&b, &fb, nodes(&fb)));
            if surface.area() == 0.0 {
                continue;
            }
            tested += 1;
            let pair = ContactPair {
                target: 0,
                contactor: 1,
                surface,
            };
            let blk = local_conductance_block(&pair, 0.01);
            let scale = pair.area() / 0.01;
            for i in 0..8 {
                let row: f64 = (0..8).map(|j| blk[8 * i + j]).sum();
                assert!(row.abs() <= 1e-12 * scale, "row {i} sums to {row}");
                for j in 0..8 {
                    assert_eq!(blk[8 * i + j], blk[8 * j + i], "not symmetric");
                    if i != j {
                        assert!(
                            blk[8 * i + j] <= 0.0,
                            "entry ({i}, {j}) = {}",
                            blk[8 * i + j]
                        );
                    }
                }
            }
            // Same total conductance as the pair's S/Rc.
            let cross: f64 = (0..4)
                .flat_map(|i| (4..8).map(move |j| (i, j)))
                .map(|(i, j)| -blk[8 * i + j])
                .sum();
            assert!((cross - scale).abs() <= 1e-12 * scale, "{cross} vs {scale}");
        }
    }
}
