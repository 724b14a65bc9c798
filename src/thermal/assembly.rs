//! Distributed assembly of the thermal operators: each rank adds the
//! element blocks of its owned elements (and the face terms of faces whose
//! first node it owns) into PETSc matrices with global (PETSc) numbering.

use crate::contact::{
    local_conductance_block, rank_one_conductance_block, ContactOperator, ContactSet, DeltaT,
};
use crate::model::Model;
use crate::parallel::Layout;
use crate::petsc::{Matrix, Petsc, Result, Vector};
use crate::scenario::{CapacityKind, ConductionKind};

use super::element;

/// The unconstrained operators of M Ṫ + K T = f.
pub struct Operators<'p> {
    /// Capacity M (consistent or lumped, stored in K's pattern).
    pub capacity: Matrix<'p>,
    /// Conductivity plus convection, K + H.
    pub stiffness: Matrix<'p>,
    /// Constant load f (sources, fluxes, convection ambient terms).
    pub load: Vector<'p>,
    /// Row sums of M: M·T summed is the stored heat.
    pub capacity_rowsum: Vector<'p>,
    /// Load of flux and source terms only (for the energy account).
    pub load_flux: Vector<'p>,
    /// Load of convection ambient terms only.
    pub load_convection: Vector<'p>,
}

/// Node couplings the contact conductance adds to the element pattern.
fn contact_couplings(model: &Model, contacts: &ContactSet, mode: DeltaT) -> Vec<(u32, u32)> {
    let mesh = &model.mesh;
    let mut extra = Vec::new();
    match mode {
        DeltaT::Local => {
            for p in &contacts.all {
                for &a in &mesh.tets[p.target as usize] {
                    for &b in &mesh.tets[p.contactor as usize] {
                        extra.push((a, b));
                    }
                }
            }
        }
        DeltaT::Average => {
            // Contact nodes of each body pair couple to every node of both bodies.
            for ((ba, bb), nodes) in average_rows(model, &contacts.all) {
                let (ra, rb) = (model.bodies[ba].node_range, model.bodies[bb].node_range);
                for (&n, _) in nodes.iter() {
                    extra.extend((ra.0..ra.1).chain(rb.0..rb.1).map(|m| (n, m)));
                }
            }
        }
    }
    extra.sort_unstable();
    extra.dedup();
    extra
}

/// Per (target body, contactor body): Σ over pairs of g v_i per node (seed
/// 000 sec 5.2, exact form): rows of the average-ΔT conductance.
fn average_rows(
    model: &Model,
    pairs: &[crate::contact::ContactPair],
) -> std::collections::BTreeMap<(usize, usize), std::collections::BTreeMap<u32, f64>> {
    let mut rows: std::collections::BTreeMap<(usize, usize), std::collections::BTreeMap<u32, f64>> =
        Default::default();
    for p in pairs {
        let (t, c) = (p.target as usize, p.contactor as usize);
        let g = p.area() / model.contact_resistance(t, c);
        let key = (model.mesh.body[t] as usize, model.mesh.body[c] as usize);
        let r = rows.entry(key).or_default();
        for i in 0..4 {
            *r.entry(model.mesh.tets[t][i]).or_default() += g * p.surface.w_target[i];
            *r.entry(model.mesh.tets[c][i]).or_default() -= g * p.surface.w_contactor[i];
        }
    }
    rows
}

/// Collective. Assemble M, K + H + Ch and f for this rank's share of
/// `model`, with the contact conductance of `contacts` (seed 000 eqs 24–30).
pub fn assemble<'p>(
    petsc: &'p Petsc,
    model: &Model,
    layout: &Layout,
    contacts: &ContactSet,
) -> Result<Operators<'p>> {
    let mode = model.contact.as_ref().map_or(DeltaT::Local, |c| c.delta_t);
    let block = match model.contact.as_ref().map(|c| c.operator) {
        Some(ContactOperator::RankOne) => rank_one_conductance_block,
        _ => local_conductance_block,
    };
    let extra = contact_couplings(model, contacts, mode);
    let (d_nnz, o_nnz) = layout.preallocation(&model.mesh, &extra);
    let owned = layout.num_owned();
    let mut capacity = Matrix::new_aij(petsc, owned, &d_nnz, &o_nnz)?;
    let mut stiffness = Matrix::new_aij(petsc, owned, &d_nnz, &o_nnz)?;
    let mut load_flux = Vector::new(petsc, owned)?;
    let mut load_convection = Vector::new(petsc, owned)?;
    load_flux.set(0.0)?;
    load_convection.set(0.0)?;
    let g = |n: u32| layout.global_of[n as usize] as i32;

    for &e in &layout.owned_elems {
        let e = e as usize;
        let mat = model.material_of(e);
        let geo = crate::geometry::tet4_geometry(&model.mesh.element_coords(e));
        let idx = model.mesh.tets[e].map(g);
        let k = element::conductivity(&geo, mat.conductivity);
        let rho_c = mat.density * mat.specific_heat;
        let m = match model.thermal.capacity {
            CapacityKind::Consistent => element::capacity_consistent(&geo, rho_c),
            CapacityKind::Lumped => element::capacity_lumped(&geo, rho_c),
        };
        stiffness.add_values(&idx, &idx, &k)?;
        capacity.add_values(&idx, &idx, &m)?;
        let q = model.thermal.source[model.mesh.body[e] as usize];
        if q != 0.0 {
            load_flux.set_values(&idx, &element::source_load(&geo, q), true)?;
        }
    }
    let coords = |f: &[u32; 3]| f.map(|n| model.mesh.nodes[n as usize]);
    for (f, q) in &model.thermal.flux {
        if layout.owns(f[0]) {
            let (area, _) = element::triangle_area_normal(&coords(f));
            load_flux.set_values(&f.map(g), &element::face_flux_load(area, *q), true)?;
        }
    }
    for (f, h, tenv) in &model.thermal.convection {
        if layout.owns(f[0]) {
            let (area, _) = element::triangle_area_normal(&coords(f));
            let (hm, hl) = element::face_convection(area, *h, *tenv);
            let idx = f.map(g);
            stiffness.add_values(&idx, &idx, &hm)?;
            load_convection.set_values(&idx, &hl, true)?;
        }
    }
    // Contact conductance; the capacity gets explicit zeros at the same
    // places so every operator shares one pattern.
    match mode {
        DeltaT::Local => {
            for p in &contacts.local {
                let (t, c) = (p.target as usize, p.contactor as usize);
                let rc = model.contact_resistance(t, c);
                if !rc.is_finite() {
                    continue;
                }
                let mut idx = [0i32; 8];
                for i in 0..4 {
                    idx[i] = g(model.mesh.tets[t][i]);
                    idx[4 + i] = g(model.mesh.tets[c][i]);
                }
                stiffness.add_values(&idx, &idx, &block(p, rc))?;
                capacity.add_values(&idx, &idx, &[0.0; 64])?;
            }
        }
        DeltaT::Average => {
            // Row i: g v_i (a_A − a_B), a_X = node capacity / body capacity.
            let cap = model.node_capacity();
            let body_cap: Vec<f64> = model
                .bodies
                .iter()
                .map(|b| {
                    cap[b.node_range.0 as usize..b.node_range.1 as usize]
                        .iter()
                        .sum()
                })
                .collect();
            for ((ba, bb), rows) in average_rows(model, &contacts.local) {
                let (ra, rb) = (model.bodies[ba].node_range, model.bodies[bb].node_range);
                let cols: Vec<u32> = (ra.0..ra.1).chain(rb.0..rb.1).collect();
                let a: Vec<f64> = cols
                    .iter()
                    .map(|&m| {
                        if m >= ra.0 && m < ra.1 {
                            cap[m as usize] / body_cap[ba]
                        } else {
                            -cap[m as usize] / body_cap[bb]
                        }
                    })
                    .collect();
                let gcols: Vec<i32> = cols.iter().map(|&m| g(m)).collect();
                let zeros = vec![0.0; cols.len()];
                for (&n, &w) in &rows {
                    let vals: Vec<f64> = a.iter().map(|x| w * x).collect();
                    stiffness.add_values(&[g(n)], &gcols, &vals)?;
                    capacity.add_values(&[g(n)], &gcols, &zeros)?;
                    // Explicit zeros at the transposed places: one symmetric
                    // pattern for every operator (and for the bounded form).
                    stiffness.add_values(&gcols, &[g(n)], &zeros)?;
                    capacity.add_values(&gcols, &[g(n)], &zeros)?;
                }
            }
        }
    }
    capacity.assemble()?;
    stiffness.assemble()?;
    if model.thermal.conduction == ConductionKind::Bounded {
        let transposed = stiffness.transpose()?;
        stiffness.update_owned_rows(&transposed, |r, c, v, t| {
            super::monotone::upwind_row(r, c, v, t);
        })?;
    }
    load_flux.assemble()?;
    load_convection.assemble()?;
    let mut load = load_flux.duplicate()?;
    load.copy_from(&load_flux)?;
    load.axpy(1.0, &load_convection)?;
    let mut capacity_rowsum = load.duplicate()?;
    capacity.row_sums(&mut capacity_rowsum)?;
    Ok(Operators {
        capacity,
        stiffness,
        load,
        capacity_rowsum,
        load_flux,
        load_convection,
    })
}
