//! Distributed assembly of the thermal operators: each rank adds the
//! element blocks of its owned elements (and the face terms of faces whose
//! first node it owns) into PETSc matrices with global (PETSc) numbering.

use crate::model::Model;
use crate::parallel::Layout;
use crate::petsc::{Matrix, Petsc, Result, Vector};
use crate::scenario::CapacityKind;

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

/// Collective. Assemble M, K + H and f for this rank's share of `model`.
pub fn assemble<'p>(petsc: &'p Petsc, model: &Model, layout: &Layout) -> Result<Operators<'p>> {
    let (d_nnz, o_nnz) = layout.preallocation(&model.mesh, &[]);
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
        let geo = element::tet4_geometry(&model.mesh.element_coords(e));
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
    capacity.assemble()?;
    stiffness.assemble()?;
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
