//! Does a mesh keep the discrete maximum principle? The positive
//! off-diagonal entries of its conductance matrix (issue 15, item 2).
//!
//! Backward Euler with a lumped capacity solves A Tⁿ⁺¹ = M_L/Δt Tⁿ + ...
//! with A = M_L/Δt + K (seed 000 eq 22 with θ = 1). When every off-diagonal
//! entry of K is ≤ 0, A is an M-matrix (diagonally dominant, Z-sign
//! pattern), A⁻¹ ≥ 0, and every new temperature is a weighted mean of the
//! old ones and the boundary values: no temperature leaves the range of the
//! initial and boundary data. An element makes K_ij > 0 on the edge (i, j)
//! when the dihedral angle at the opposite edge is obtuse (K_e,ij =
//! −k (A_i A_j / 9V) cos θ_ij, with A the face areas); assembled over the
//! elements around an edge the entry may still be ≤ 0. Pure: no MPI, no PETSc.

use std::collections::HashMap;

use super::element::conductivity;
use crate::geometry::tet4_geometry;
use crate::mesh::TetMesh;

/// The positive off-diagonals of a mesh's conductance matrix (k = 1).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OffDiagonalReport {
    /// Elements with at least one positive off-diagonal entry.
    pub elements_positive: usize,
    /// Largest K_e,ij / sqrt(K_e,ii K_e,jj) over elements and i ≠ j.
    pub element_max: f64,
    /// Edges whose assembled entry K_ij is positive.
    pub edges_positive: usize,
    /// Number of edges.
    pub edges: usize,
    /// Largest assembled K_ij / sqrt(K_ii K_jj) over edges (negative when
    /// every entry is ≤ 0: then the mesh keeps the bounds).
    pub assembled_max: f64,
}

impl OffDiagonalReport {
    /// Whether backward Euler with a lumped capacity keeps the bounds on
    /// this mesh at any time step (every assembled off-diagonal ≤ 0, to
    /// round-off).
    pub fn keeps_bounds(&self) -> bool {
        self.assembled_max <= 1e-12
    }
}

/// Discrete upwinding of one row of an operator K whose rows and columns
/// sum to zero (Kuzmin's low-order operator, generalised to a
/// non-symmetric K): `vals` is row i of K over the stored columns `cols`,
/// `transposed` row i of Kᵀ (column i of K) at the same columns. Every
/// off-diagonal pair with w_ij = max(0, K_ij, K_ji) > 0 gets a link of
/// conductance w_ij: K_ij −= w_ij, K_ii += w_ij. Over the matrix this adds
/// the graph Laplacian of the links (symmetric, rows and columns summing to
/// zero), so K keeps its row and column sums (constants stay steady, heat
/// is conserved, and the heat between two bodies is unchanged), stays
/// positive semi-definite where it was symmetric, and has no positive
/// off-diagonal entry: with a lumped capacity and θ = 1 the system is an
/// M-matrix. Nothing changes where no coupling is positive. Returns the
/// conductance moved onto the diagonal.
pub fn upwind_row(row: i32, cols: &[i32], vals: &mut [f64], transposed: &[f64]) -> f64 {
    let mut moved = 0.0;
    let mut diag = None;
    for (k, &c) in cols.iter().enumerate() {
        if c == row {
            diag = Some(k);
            continue;
        }
        let w = vals[k].max(transposed[k]).max(0.0);
        if w > 0.0 {
            vals[k] -= w;
            moved += w;
        }
    }
    if let Some(k) = diag {
        vals[k] += moved;
    }
    moved
}

/// Seed 000 eq 16 per element, assembled with k = 1.
pub fn conductance_off_diagonals(mesh: &TetMesh) -> OffDiagonalReport {
    let mut report = OffDiagonalReport {
        element_max: f64::NEG_INFINITY,
        assembled_max: f64::NEG_INFINITY,
        ..Default::default()
    };
    let mut diag = vec![0.0; mesh.nodes.len()];
    let mut edge: HashMap<(u32, u32), f64> = HashMap::new();
    for (e, tet) in mesh.tets.iter().enumerate() {
        let k = conductivity(&tet4_geometry(&mesh.element_coords(e)), 1.0);
        let mut positive = false;
        for i in 0..4 {
            diag[tet[i] as usize] += k[5 * i];
            for j in i + 1..4 {
                let kij = k[4 * i + j];
                let rel = kij / (k[5 * i] * k[5 * j]).sqrt();
                report.element_max = report.element_max.max(rel);
                positive |= kij > 0.0;
                let key = (tet[i].min(tet[j]), tet[i].max(tet[j]));
                *edge.entry(key).or_default() += kij;
            }
        }
        report.elements_positive += usize::from(positive);
    }
    report.edges = edge.len();
    for ((a, b), kij) in edge {
        let rel = kij / (diag[a as usize] * diag[b as usize]).sqrt();
        report.assembled_max = report.assembled_max.max(rel);
        report.edges_positive += usize::from(rel > 1e-12);
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{box_mesh, cylinder_mesh, CircleNodes};
    use crate::mesh::{container_mesh, nut_mesh_default};

    fn show(name: &str, r: &OffDiagonalReport) {
        println!(
            "{name}: {} of elements with K_e,ij > 0 (max {:.3} of the diagonal), \
             {} of {} edges with assembled K_ij > 0 (max {:.3})",
            r.elements_positive, r.element_max, r.edges_positive, r.edges, r.assembled_max
        );
    }

    #[test]
    fn upwinding_moves_positive_couplings_to_the_diagonal() {
        // Row 1 of a symmetric zero-row-sum operator with one positive coupling.
        let cols = [0, 1, 2, 3];
        let mut vals = [-2.0, 3.0, 0.5, -1.5];
        let moved = upwind_row(1, &cols, &mut vals, &[-2.0, 3.0, 0.5, -1.5]);
        assert_eq!(moved, 0.5);
        assert_eq!(vals, [-2.0, 3.5, 0.0, -1.5]);
        assert_eq!(vals.iter().sum::<f64>(), 0.0);
        // Nothing positive: nothing changes.
        let mut vals = [-2.0, 3.5, 0.0, -1.5];
        let same = vals;
        assert_eq!(upwind_row(1, &cols, &mut vals, &same), 0.0);
        assert_eq!(vals, [-2.0, 3.5, 0.0, -1.5]);
        // Non-symmetric: the larger of K_ij and K_ji is moved from both.
        let mut vals = [-1.0, 1.0, 0.2, -0.2];
        let moved = upwind_row(1, &cols, &mut vals, &[-1.5, 1.0, 0.6, 0.0]);
        assert!((moved - 0.6).abs() < 1e-15);
        assert!((vals[2] + 0.4).abs() < 1e-15 && (vals[1] - 1.6).abs() < 1e-15);
    }

    #[test]
    fn kuhn_boxes_keep_the_bounds() {
        // Six Kuhn tets per cube: every dihedral angle at most 90°.
        let r = conductance_off_diagonals(&box_mesh([0.0; 3], [1.0, 0.5, 0.3], 0.1).unwrap());
        show("box", &r);
        assert_eq!(r.elements_positive, 0);
        assert!(r.keeps_bounds());
    }

    #[test]
    fn an_obtuse_tet_is_seen() {
        // A flat tet: the apex just above the centroid of a wide base makes
        // the dihedral angles at the base edges nearly 180° (obtuse).
        let m = TetMesh::one_body(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.33, 0.33, 0.05],
            ],
            vec![[0, 1, 2, 3]],
        );
        let r = conductance_off_diagonals(&m);
        assert_eq!(r.elements_positive, 1);
        assert!(r.element_max > 0.0 && !r.keeps_bounds(), "{r:?}");
    }

    #[test]
    fn generators_report() {
        // Measured figures, printed for the README (`--nocapture`); the nut
        // and the container are asserted in tests/packing.rs by the bounds
        // of the runs themselves.
        show(
            "nut",
            &conductance_off_diagonals(&nut_mesh_default([0.0; 3]).unwrap()),
        );
        show(
            "container",
            &conductance_off_diagonals(
                &container_mesh([0.0; 3], 0.225, 0.02, 0.02, 0.6, 0.02).unwrap(),
            ),
        );
        for (name, nodes) in [
            ("cylinder (inscribed)", CircleNodes::Inscribed),
            ("cylinder (area preserving)", CircleNodes::AreaPreserving),
        ] {
            let m = cylinder_mesh([0.0; 3], 1.0, 0.1, 0.08, nodes).unwrap();
            show(name, &conductance_off_diagonals(&m));
        }
    }
}
