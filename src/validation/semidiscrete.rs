//! Exact time integration of the semi-discrete heat equation
//! M Ṫ + K T = 0 with Dirichlet nodes, for small meshes: the reference that
//! isolates the time-stepping error of the theta method (seed 000 eq 22)
//! from the spatial error.
//!
//! With free (f) and prescribed (d) nodes, T_f(t) = T_s + e^{−M_ff⁻¹K_ff t}(T_f(0) − T_s),
//! T_s = −K_ff⁻¹ K_fd T_d, evaluated through the symmetric generalised
//! eigenproblem K_ff v = λ M_ff v (Cholesky M_ff = L Lᵀ, C = L⁻¹ K_ff L⁻ᵀ).
//! Dense: meant for a few hundred nodes. Uses only the element kernels.

use nalgebra::{DMatrix, DVector};

use crate::mesh::TetMesh;
use crate::thermal::element;

/// Dense global capacity and conductivity matrices of a one-material mesh.
pub fn dense_operators(
    mesh: &TetMesh,
    k: f64,
    rho_c: f64,
    lumped: bool,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = mesh.nodes.len();
    let mut m = DMatrix::zeros(n, n);
    let mut kk = DMatrix::zeros(n, n);
    for e in 0..mesh.tets.len() {
        let g = crate::geometry::tet4_geometry(&mesh.element_coords(e));
        let ke = element::conductivity(&g, k);
        let me = if lumped {
            element::capacity_lumped(&g, rho_c)
        } else {
            element::capacity_consistent(&g, rho_c)
        };
        let t = mesh.tets[e];
        for i in 0..4 {
            for j in 0..4 {
                kk[(t[i] as usize, t[j] as usize)] += ke[4 * i + j];
                m[(t[i] as usize, t[j] as usize)] += me[4 * i + j];
            }
        }
    }
    (m, kk)
}

/// The exact semi-discrete solution at time `t` for initial values `t0`
/// and nodes `dirichlet` held at their values in `t0`.
pub fn semidiscrete_solution(
    m: &DMatrix<f64>,
    k: &DMatrix<f64>,
    t0: &[f64],
    dirichlet: &[u32],
    t: f64,
) -> Vec<f64> {
    let n = t0.len();
    let mut is_d = vec![false; n];
    for &d in dirichlet {
        is_d[d as usize] = true;
    }
    let free: Vec<usize> = (0..n).filter(|&i| !is_d[i]).collect();
    let dn: Vec<usize> = (0..n).filter(|&i| is_d[i]).collect();
    let nf = free.len();
    let sub = |a: &DMatrix<f64>, r: &[usize], c: &[usize]| {
        DMatrix::from_fn(r.len(), c.len(), |i, j| a[(r[i], c[j])])
    };
    let mff = sub(m, &free, &free);
    let kff = sub(k, &free, &free);
    let kfd = sub(k, &free, &dn);
    let td = DVector::from_iterator(dn.len(), dn.iter().map(|&i| t0[i]));
    let tf0 = DVector::from_iterator(nf, free.iter().map(|&i| t0[i]));
    let ts = -kff
        .clone()
        .lu()
        .solve(&(&kfd * &td))
        .expect("K_ff is non-singular with at least one Dirichlet node");
    let l = mff.cholesky().expect("M_ff is SPD").l();
    let linv = l
        .clone()
        .try_inverse()
        .expect("Cholesky factor is invertible");
    let c = &linv * &kff * linv.transpose();
    let c = (&c + c.transpose()) * 0.5;
    let eig = c.symmetric_eigen();
    let u0 = l.transpose() * (tf0 - &ts);
    let q = &eig.eigenvectors;
    let mut coef = q.transpose() * u0;
    for (i, lam) in eig.eigenvalues.iter().enumerate() {
        coef[i] *= (-lam * t).exp();
    }
    let tf = ts + linv.transpose() * (q * coef);
    let mut out = t0.to_vec();
    for (i, &f) in free.iter().enumerate() {
        out[f] = tf[i];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;

    #[test]
    fn reaches_the_linear_steady_state_and_keeps_dirichlet() {
        let mesh = box_mesh([0.0; 3], [1.0, 0.2, 0.2], 0.2).unwrap();
        let (m, k) = dense_operators(&mesh, 1.0, 100.0, false);
        let xmax = mesh.set_nodes("xmax").unwrap();
        let mut t0 = vec![0.0; mesh.nodes.len()];
        for &n in &xmax {
            t0[n as usize] = 1.0;
        }
        // The insulated bar ends uniform at the held value.
        let late = semidiscrete_solution(&m, &k, &t0, &xmax, 1e5);
        assert!(late.iter().all(|v| (v - 1.0).abs() < 1e-9));
        // Early, lumped capacity on non-obtuse (Kuhn) tets: the discrete
        // maximum principle holds (consistent capacity may undershoot).
        let (ml, kl) = dense_operators(&mesh, 1.0, 100.0, true);
        let early = semidiscrete_solution(&ml, &kl, &t0, &xmax, 1.0);
        assert!(early.iter().all(|v| (-1e-9..=1.0 + 1e-9).contains(v)));
        for &n in &xmax {
            assert_eq!(early[n as usize], 1.0);
        }
    }
}
