//! Highest natural frequency of a whole free body, for the explicit time
//! step of small particles (pure: no MPI).
//!
//! The per-element bound of [`element_critical_dt`](super::element::element_critical_dt)
//! is rigorous but pessimistic for a mesh: the highest mode of an
//! assembled mesh is slower than that of its stiffest element (the element
//! eigenvalue theorem, Irons 1970), and the Rayleigh bound used there is
//! itself above the element's own eigenvalue. For the 144-tet nut of seed
//! 000 sec 6 the body's exact limit 2/ω_max is 1.62× the element bound.
//! [`body_max_frequency`] computes ω_max of the linearised, unsupported
//! body with lumped masses exactly (dense symmetric eigenvalues, so only
//! for small bodies, [`BODY_EIGEN_MAX_NODES`]); supports only lower it
//! (eigenvalue interlacing), so the free body's value is safe for them too.
//! [`BodyShape`] lets copies of one template (a packing) share the result:
//! same connectivity, materials and edge lengths means congruent bodies,
//! hence the same frequencies.

use nalgebra::{DMatrix, Matrix3, Vector3};

use super::{ElasticMaterial, MechanicsError, Tet4Reference};

/// Largest body (nodes) whose frequency is computed exactly; larger bodies
/// keep the element bound (a dense eigenproblem of 3 × nodes unknowns).
pub const BODY_EIGEN_MAX_NODES: usize = 400;

/// ω_max (rad/s) of the lumped-mass, linear-elastic, unsupported body at
/// positions `x` with elements `tets` (indices into `x`; every node used)
/// of materials `materials[e]` (positively oriented, as in the meshes).
/// Errors on an inverted or degenerate element, naming it.
pub fn body_max_frequency(
    x: &[Vector3<f64>],
    tets: &[[u32; 4]],
    materials: &[ElasticMaterial],
) -> Result<f64, MechanicsError> {
    let n = x.len();
    let mut k = DMatrix::<f64>::zeros(3 * n, 3 * n);
    let mut mass = vec![0.0; n];
    for (e, (t, m)) in tets.iter().zip(materials).enumerate() {
        let r = Tet4Reference::new(&t.map(|i| x[i as usize])).map_err(|err| err.at_element(e))?;
        let (g, vol) = (r.reference_gradients(), r.volume0);
        let (mu, lambda) = m.lame();
        for a in 0..4 {
            // Not numbered in the seeds: row-sum lumped mass ρ V/4 per node (as the solver's).
            mass[t[a] as usize] += m.density * vol / 4.0;
            for b in 0..4 {
                // Standard (linear Tet4): K_ab = V (λ g_a g_bᵀ + μ g_b g_aᵀ + μ (g_a·g_b) I).
                let blk = (g[a] * g[b].transpose()) * lambda
                    + (g[b] * g[a].transpose()) * mu
                    + Matrix3::identity() * (mu * g[a].dot(&g[b]));
                for i in 0..3 {
                    for j in 0..3 {
                        k[(3 * t[a] as usize + i, 3 * t[b] as usize + j)] += vol * blk[(i, j)];
                    }
                }
            }
        }
    }
    if let Some(i) = mass.iter().position(|&m| m <= 0.0) {
        return Err(MechanicsError::InvalidParameter(format!(
            "node {i} belongs to no element"
        )));
    }
    // M^{-1/2} K M^{-1/2}: symmetric, with the eigenvalues ω² of M⁻¹K.
    let scale: Vec<f64> = (0..3 * n).map(|i| mass[i / 3].sqrt().recip()).collect();
    for j in 0..3 * n {
        for i in 0..3 * n {
            k[(i, j)] *= scale[i] * scale[j];
        }
    }
    let top = k.symmetric_eigenvalues().max();
    Ok(top.max(0.0).sqrt())
}

/// Stable central-difference step 2/ω · (√(1+ξ²) − ξ) for the highest
/// frequency ω with damping ratio ξ (ξ = η ω / M for the viscous stress,
/// the same relation as in the element bound).
pub fn stable_step(omega: f64, xi: f64) -> f64 {
    // Not numbered in the seeds: central-difference limit Δt = (2/ω)(√(1+ξ²) − ξ).
    2.0 / omega * ((1.0 + xi * xi).sqrt() - xi)
}

/// What makes two bodies share their frequencies: the element connectivity
/// in local numbering, each element's material index, and the six edge
/// lengths of every element (equal within 1e-9 relative).
#[derive(Debug, Clone, PartialEq)]
pub struct BodyShape {
    tets: Vec<[u32; 4]>,
    materials: Vec<u32>,
    edges: Vec<f64>,
}

impl BodyShape {
    /// Shape of a body with local elements `tets` at `x`, materials `mat`.
    pub fn new(x: &[Vector3<f64>], tets: &[[u32; 4]], mat: &[u32]) -> Self {
        const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
        let edges = tets
            .iter()
            .flat_map(|t| EDGES.map(|(i, j)| (x[t[i] as usize] - x[t[j] as usize]).norm()))
            .collect();
        BodyShape {
            tets: tets.to_vec(),
            materials: mat.to_vec(),
            edges,
        }
    }

    /// Whether the two bodies are congruent (so have equal frequencies):
    /// a shared face fixes the placement of a neighbour up to reflection,
    /// so equal connectivity and edge lengths mean an isometric copy.
    pub fn congruent(&self, other: &BodyShape) -> bool {
        self.tets == other.tets
            && self.materials == other.materials
            && self.edges.len() == other.edges.len()
            && self
                .edges
                .iter()
                .zip(&other.edges)
                .all(|(a, b)| (a - b).abs() <= 1e-9 * a.max(*b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::explicit::{
        internal_forces, lumped_masses, mesh_elements, update_nodes, NodeUpdate, ThermalLoad,
    };
    use crate::mechanics::material::table1_concrete;
    use crate::mesh::nut::nut_mesh_default;
    use crate::mesh::TetMesh;

    fn vectors(mesh: &TetMesh) -> Vec<Vector3<f64>> {
        mesh.nodes.iter().map(|p| Vector3::from(*p)).collect()
    }

    fn frequency(mesh: &TetMesh, mat: ElasticMaterial) -> f64 {
        body_max_frequency(&vectors(mesh), &mesh.tets, &vec![mat; mesh.tets.len()]).unwrap()
    }

    /// Largest |u| reached over `steps` undamped central-difference steps
    /// of the real finite-strain kernels from a tiny random displacement.
    fn growth(mesh: &TetMesh, mat: ElasticMaterial, dt: f64, steps: usize) -> f64 {
        let elements = mesh_elements(mesh, 1).unwrap();
        let n = mesh.nodes.len();
        let mass = lumped_masses(&elements, &[mat], n).unwrap();
        let x0 = vectors(mesh);
        let mut x = x0.clone();
        let mut v = vec![Vector3::zeros(); n];
        let mut seed = 7u64;
        for p in x.iter_mut() {
            for d in 0..3 {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                p[d] += 1e-12 * ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5);
            }
        }
        let bc = vec![[None; 3]; n];
        let update = NodeUpdate {
            dt,
            gravity: Vector3::zeros(),
            mass_damping: 0.0,
        };
        let mut worst: f64 = 0.0;
        for _ in 0..steps {
            let mut f = vec![Vector3::zeros(); n];
            // An inverted element or a non-finite state: it blew up.
            if internal_forces(&elements, &[mat], &x, &v, ThermalLoad::none(), &mut f, None)
                .and_then(|_| update_nodes(&update, &mass, &f, &bc, &mut x, &mut v))
                .is_err()
            {
                return f64::INFINITY;
            }
            for (a, b) in x.iter().zip(&x0) {
                worst = worst.max((a - b).norm());
            }
            if worst > 1.0 {
                break;
            }
        }
        worst
    }

    #[test]
    fn the_nut_is_stable_just_below_its_limit_and_not_above() {
        let mesh = nut_mesh_default([0.0; 3]).unwrap();
        let mat = table1_concrete();
        let omega = frequency(&mesh, mat);
        let dt = stable_step(omega, 0.0);
        // The element bound is safe but pessimistic: the body's limit is larger.
        let element = crate::mechanics::critical_dt(&mesh, &[mat]).unwrap().dt;
        println!(
            "nut: body limit {dt:e} s = {:.2} x the element bound",
            dt / element
        );
        assert!(dt > 1.4 * element, "body {dt:e} vs element {element:e}");
        // The real solver: bounded at 0.98 of the limit, blows up at 1.02.
        let below = growth(&mesh, mat, 0.98 * dt, 4000);
        let above = growth(&mesh, mat, 1.02 * dt, 4000);
        assert!(below < 1e-10, "stable step grew to {below:e}");
        assert!(above > 1e-6, "unstable step stayed at {above:e}");
    }

    #[test]
    fn congruent_copies_are_recognised_and_others_not() {
        let mesh = nut_mesh_default([0.0; 3]).unwrap();
        let x = vectors(&mesh);
        let mats = vec![0; mesh.tets.len()];
        let a = BodyShape::new(&x, &mesh.tets, &mats);
        // Rotated 30° about z and moved: congruent, same frequency.
        let rot = nalgebra::Rotation3::from_euler_angles(0.3, -0.2, 0.5);
        let moved: Vec<Vector3<f64>> = x
            .iter()
            .map(|p| rot * p + Vector3::new(1.0, 2.0, 3.0))
            .collect();
        assert!(a.congruent(&BodyShape::new(&moved, &mesh.tets, &mats)));
        let mat = table1_concrete();
        let mats_e = vec![mat; mesh.tets.len()];
        let w0 = body_max_frequency(&x, &mesh.tets, &mats_e).unwrap();
        let w1 = body_max_frequency(&moved, &mesh.tets, &mats_e).unwrap();
        assert!((w0 - w1).abs() <= 1e-9 * w0);
        // Stretched by 1 %: not congruent.
        let big: Vec<Vector3<f64>> = x.iter().map(|p| p * 1.01).collect();
        assert!(!a.congruent(&BodyShape::new(&big, &mesh.tets, &mats)));
        // Another material on one element: not congruent.
        let mut other = mats.clone();
        other[5] = 1;
        assert!(!a.congruent(&BodyShape::new(&x, &mesh.tets, &other)));
    }

    #[test]
    fn a_degenerate_element_is_an_error() {
        let x = vec![
            Vector3::zeros(),
            Vector3::x(),
            Vector3::y(),
            Vector3::x() + Vector3::y(),
        ];
        let err = body_max_frequency(&x, &[[0, 1, 2, 3]], &[table1_concrete()]).unwrap_err();
        assert!(err.to_string().contains("element 0"), "{err}");
    }
}
