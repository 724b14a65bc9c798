//! The explicit time step: the exact highest frequency of each small free
//! body, the element bound in larger ones (seed 004 sec 2, the Tet4 of
//! [`crate::mechanics::element`]), and the contact penalty as a stiffer
//! modulus.

use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use nalgebra::Vector3;

use crate::error::{Error, Result};
use crate::mechanics::element::{characteristic_length, element_critical_dt, to_vectors};
use crate::mechanics::frequency::{
    body_max_frequency, stable_step, BodyShape, BODY_EIGEN_MAX_NODES,
};
use crate::mechanics::ElasticMaterial;
use crate::model::Model;
use crate::parallel::Part;

/// Collective. The explicit step of the free elements `free` (local
/// indices, Tet4 only; `hex_bound` is the Hex8 elements' step and
/// shortest length) of this rank's part (`pn` the contact penalty, if any): the
/// scenario's, checked against the critical one, or safety × critical, cut
/// to fill `coupling_dt`. `particle_w2`: per body, the square of the
/// highest frequency its particles add (issue 21), added to the body's
/// like the joints'. `sphere_dt`: the free spheres' stable step (issue 21).
/// Returns (Δt, substeps per thermal step, the smallest characteristic
/// element length over the ranks).
#[allow(clippy::too_many_arguments)]
pub(super) fn time_step(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    materials: &[ElasticMaterial],
    free: &[usize],
    hex_bound: (f64, f64),
    pn: Option<f64>,
    coupling_dt: f64,
    particle_w2: &[(u32, f64)],
    sphere_dt: f64,
) -> Result<(f64, u64, f64)> {
    let mm = model.mechanics.as_ref().expect("mechanics model");
    let mesh = &part.mesh;
    // Time step: the exact highest frequency of each small free body
    // (congruent copies share it), the element bound in larger ones; the
    // contact penalty acts as a stiffer modulus. A small body is never
    // split over ranks, so its elements are all here.
    let mut dt_local = f64::INFINITY;
    let mut min_len = f64::INFINITY;
    let mut body_elems: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
    for &e in free {
        body_elems.entry(mesh.body[e]).or_default().push(e);
    }
    let mut shapes: Vec<(BodyShape, f64)> = Vec::new();
    let mut local_error = None;
    let mut joint_w2 = joint_frequencies(comm, model, part);
    for &(b, w2) in particle_w2 {
        *joint_w2.entry(b).or_insert(0.0) += w2;
    }
    for (&b, owned) in &body_elems {
        for &e in owned {
            min_len = min_len.min(characteristic_length(&to_vectors(&mesh.element_coords(e))));
        }
        let body = &model.bodies[b as usize];
        let whole = owned.len() as u32 == body.elem_range.1 - body.elem_range.0;
        let body_dt = if whole {
            body_frequency(part, materials, owned, &mut shapes)
                .map_err(|err| Error::Mechanics(format!("body `{}`: {err}", body.name)))
        } else {
            Ok(None)
        };
        match body_dt.unwrap_or_else(|err| {
            local_error.get_or_insert(err);
            None
        }) {
            Some((omega, eta_over_m, m_min)) => {
                // Joints add their springs: ω² ≤ ω_body² + ω_joints² (both
                // stiffnesses positive semi-definite over the same masses).
                let omega = (omega * omega + joint_w2.get(&b).copied().unwrap_or(0.0)).sqrt();
                dt_local = dt_local.min(stable_step(omega, eta_over_m * omega));
                if let Some(pn) = pn {
                    // Not numbered in the seeds: a penalty p_n acts like a modulus, Δt ≤ (2/ω) sqrt(M/p_n).
                    dt_local = dt_local.min(2.0 / omega * (m_min / pn).sqrt());
                }
            }
            None => {
                for &e in owned {
                    let xe = to_vectors(&mesh.element_coords(e));
                    let mat = &materials[part.elem_material[e] as usize];
                    match joint_w2.get(&b) {
                        None => dt_local = dt_local.min(element_critical_dt(&xe, mat)),
                        Some(w2) => {
                            // Not numbered in the seeds: ω_e = 2c/L, with the joints' ω² added.
                            let omega_e = 2.0 * mat.p_wave_speed() / characteristic_length(&xe);
                            let omega = (omega_e * omega_e + w2).sqrt();
                            let eta_over_m = mat.viscosity / mat.p_wave_modulus();
                            dt_local = dt_local.min(stable_step(omega, eta_over_m * omega));
                        }
                    }
                    if let Some(pn) = pn {
                        // Not numbered in the seeds: a penalty p_n acts like a modulus, Δt ≤ L sqrt(ρ/p_n).
                        dt_local =
                            dt_local.min(characteristic_length(&xe) * (mat.density / pn).sqrt());
                    }
                }
            }
        }
    }
    crate::parallel::agree(comm, local_error.map_or(Ok(()), Err))?;
    // The Hex8 elements (issue 21): their own bound, and shortest length.
    dt_local = dt_local.min(hex_bound.0);
    min_len = min_len.min(hex_bound.1);
    // The free spheres' contacts (issue 21), the same on every rank.
    dt_local = dt_local.min(sphere_dt);
    let mut crit: f64 = 0.0;
    comm.all_reduce_into(&dt_local, &mut crit, SystemOperation::min());
    let mut min_len_all: f64 = 0.0;
    comm.all_reduce_into(&min_len, &mut min_len_all, SystemOperation::min());
    if !crit.is_finite() {
        // Nothing deforms (all bodies held): any step works.
        crit = coupling_dt;
    }
    let allowed = mm.safety * crit;
    let (dt, substeps) = match (mm.dt, mm.substeps) {
        (Some(dt), _) if dt > crit * (1.0 + 1e-12) => {
            return Err(Error::Mechanics(format!(
                "mechanics.dt = {dt:e} s exceeds the critical explicit step {crit:e} s of this \
                 mesh, materials, contact penalty and free spheres (safety × critical = {allowed:e} s)"
            )))
        }
        (Some(dt), Some(n)) => (dt, n),
        (None, Some(n)) => (allowed, n),
        (given, None) => {
            let limit = given.unwrap_or(allowed);
            let n = (coupling_dt / limit).ceil().max(1.0) as u64;
            (coupling_dt / n as f64, n)
        }
    };
    Ok((dt, substeps, min_len_all))
}

/// Collective. Per jointed body: a bound on the square of the highest
/// frequency of its joints' springs alone, max over nodes of 2 Σ k_j / m
/// (Gershgorin; each joint corner pair is an isotropic spring
/// k_j = p_f / h × A / 3, the node's mass at least ρ V / 4 of its tet).
/// A split body's owner of a node holds every joint at it (though perhaps
/// not the joint's tets: a continuum node of a body jointed on a set,
/// whose mass then comes from the model): the max over the owned nodes
/// here, then over the ranks.
fn joint_frequencies(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
) -> std::collections::HashMap<u32, f64> {
    let mut out = std::collections::HashMap::new();
    let mesh = &part.mesh;
    let nl = part.node_gid.len();
    let (mut k_sum, mut m_min) = (vec![0.0; nl], vec![f64::INFINITY; nl]);
    for j in &part.joints {
        let f = &j.faces;
        let Some(fm) = model.materials[j.material as usize].fracture else {
            continue;
        };
        let k = fm.penalty / crate::fracture::insert::joint_size(f.area) * f.area / 3.0;
        for (side, corners) in [(0, &f.a), (1, &f.b)] {
            let m = match part.local_element(f.tets[side]) {
                Some(e) => {
                    let e = e as usize;
                    model.materials[part.elem_material[e] as usize].density * mesh.element_volume(e)
                        / 4.0
                }
                // A tet of another rank (a joint across the cut).
                None => model_quarter_mass(model, j.body as usize, f.tets[side]),
            };
            for &l in corners {
                k_sum[l as usize] += k;
                m_min[l as usize] = f64::min(m_min[l as usize], m);
            }
        }
    }
    let no = part.num_owned();
    for j in &part.joints {
        for &l in j.faces.a.iter().chain(&j.faces.b) {
            if (l as usize) < no && m_min[l as usize].is_finite() {
                let w2 = 2.0 * k_sum[l as usize] / m_min[l as usize];
                let at = out.entry(j.body).or_insert(0.0f64);
                *at = at.max(w2);
            }
        }
    }
    // Split jointed bodies: the max over the ranks holding some of each.
    let mut split: Vec<f64> = Vec::new();
    for (&b, &w2) in &out {
        if part.whole_bodies.binary_search(&b).is_err() {
            split.extend_from_slice(&[f64::from(b), w2]);
        }
    }
    for rec in crate::parallel::all_gather_f64(comm, &split).chunks_exact(2) {
        if let Some(at) = out.get_mut(&(rec[0] as u32)) {
            *at = at.max(rec[1]);
        }
    }
    out
}

/// The quarter mass ρ V / 4 of element `elem` (global id) of body `b`, a
/// body of its own source mesh, from the model: the bits of the part's
/// own (the same moved corners, the same volume).
fn model_quarter_mass(model: &Model, b: usize, elem: u32) -> f64 {
    let body = &model.bodies[b];
    let crate::model::BodySource::Mesh { mesh, motion } = &body.source else {
        unreachable!("a split body has its own source mesh")
    };
    let src = &model.meshes[*mesh as usize];
    let e = (elem - body.elem_range.0) as usize;
    let x = src.mesh.tets[e].map(|n| motion.apply(src.mesh.nodes[n as usize]));
    // Not numbered in the seeds: row-sum lumped mass ρ V0/4 per node of a Tet4.
    model.materials[src.material[e] as usize].density * crate::mesh::tet_signed_volume(&x) / 4.0
}

/// For a free body of elements `elems` small enough for its exact highest
/// frequency ([`BODY_EIGEN_MAX_NODES`]): (ω_max, the largest η/M, the
/// smallest P-wave modulus M) of its elements; `None` for larger bodies.
/// `shapes` caches ω_max of the shapes seen (copies of one template).
fn body_frequency(
    part: &Part,
    materials: &[ElasticMaterial],
    elems: &[usize],
    shapes: &mut Vec<(BodyShape, f64)>,
) -> std::result::Result<Option<(f64, f64, f64)>, crate::mechanics::MechanicsError> {
    let mesh = &part.mesh;
    // The body's nodes in ascending global id (the same numbering on any rank).
    let mut nodes: Vec<u32> = elems.iter().flat_map(|&e| mesh.tets[e]).collect();
    nodes.sort_unstable_by_key(|&l| part.node_gid[l as usize]);
    nodes.dedup();
    if nodes.len() > BODY_EIGEN_MAX_NODES {
        return Ok(None);
    }
    let local = |l: u32| {
        nodes
            .binary_search_by_key(&part.node_gid[l as usize], |&k| part.node_gid[k as usize])
            .expect("node of the body") as u32
    };
    let tets: Vec<[u32; 4]> = elems.iter().map(|&e| mesh.tets[e].map(local)).collect();
    let mat_ids: Vec<u32> = elems.iter().map(|&e| part.elem_material[e]).collect();
    let x: Vec<Vector3<f64>> = nodes
        .iter()
        .map(|&l| Vector3::from(mesh.nodes[l as usize]))
        .collect();
    let shape = BodyShape::new(&x, &tets, &mat_ids);
    let omega = match shapes.iter().find(|(s, _)| s.congruent(&shape)) {
        Some(&(_, w)) => w,
        None => {
            let mats: Vec<ElasticMaterial> =
                mat_ids.iter().map(|&m| materials[m as usize]).collect();
            let w = body_max_frequency(&x, &tets, &mats)?;
            shapes.push((shape, w));
            w
        }
    };
    let (mut eta_over_m, mut m_min) = (0.0_f64, f64::INFINITY);
    for &m in &mat_ids {
        let mat = &materials[m as usize];
        eta_over_m = eta_over_m.max(mat.viscosity / mat.p_wave_modulus());
        m_min = m_min.min(mat.p_wave_modulus());
    }
    Ok(Some((omega, eta_over_m, m_min)))
}
