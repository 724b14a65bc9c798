//! Distributed assembly of the thermal operators (seed 000 eqs 14–20,
//! 24–30): each rank adds the element blocks of its part, the face terms
//! of its elements' faces and its contact pairs into PETSc matrices with
//! global (PETSc) numbering, preallocated exactly from the same blocks.

use std::collections::BTreeMap;

use mpi::topology::SimpleCommunicator;

use crate::contact::gap::GapLink;
use crate::contact::{
    local_conductance_block, local_conductance_row, rank_one_conductance_block,
    rank_one_conductance_row, ContactOperator, ContactSet, DeltaT,
};
use crate::model::Model;
use crate::parallel::Part;
use crate::petsc::{Matrix, Petsc, Result, Vector};
use crate::scenario::{CapacityKind, ConductionKind};

use super::element;
use super::exchange::{Law, Laws, Unit};
use super::row_sum::{Incidence, Item, RowSum};

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
    /// Free-surface radiation to the ambient, when the scenario asks for it.
    pub radiation: Option<Radiation<'p>>,
    /// Pairs and gap links whose conductance follows the temperature, and
    /// their laws (issue 20): the step is then nonlinear.
    pub exchange: Option<(Vec<Unit>, Laws)>,
}

/// Radiation of the free surfaces (issue 20): per PETSc row, ε σ times the
/// row's free area (its faces' thirds less the contact surface's share).
pub struct Radiation<'p> {
    /// ε σ a_free per row (W/K⁴).
    pub coef: Vector<'p>,
    /// Radiation across near-field gaps: the Laplacian L of the links'
    /// σ F A shares, so the power leaving the rows is L (T + offset)⁴.
    pub gap: Option<Matrix<'p>>,
    /// Added to temperatures to make them absolute.
    pub offset: f64,
    /// The ambient's absolute temperature to the fourth.
    pub ambient4: f64,
}

/// The contact resistance of a pair (m² K/W) at mean temperature `t`: a
/// table's 1/h(T, P, penetration) or the Cooper–Mikic–Yovanovich 1/h at
/// the prescribed or the pair's penalty pressure where the material pair
/// has one (issue 20), else the scenario's Rc; infinite: no heat.
pub fn pair_resistance(model: &Model, d: &crate::contact::PairDofs, t: f64) -> f64 {
    let [a, b] = d.materials;
    let Some(c) = model.contact.as_ref() else {
        return f64::INFINITY;
    };
    let h = if let Some(table) = c.table_of(a, b) {
        let p = table.prescribed_pressure.unwrap_or(d.pressure);
        table.eval(t, p, d.penetration).0
    } else if let Some(cmy) = c.cmy[a as usize][b as usize] {
        let k = |m: u32| model.materials[m as usize].conductivity;
        let p = cmy.pressure.unwrap_or(d.pressure);
        crate::contact::conductance::cmy_conductance(k(a), k(b), &cmy, p)
    } else {
        return model.resistance(a, b);
    };
    if h > 0.0 {
        1.0 / h
    } else {
        f64::INFINITY
    }
}

/// The law of a pair whose table depends on temperature, if it has one.
pub fn pair_law(model: &Model, d: &crate::contact::PairDofs) -> Option<Law> {
    let c = model.contact.as_ref()?;
    let [a, b] = d.materials;
    let i = c.table[a as usize][b as usize]?;
    let table = &c.tables[i];
    table.depends_on_temperature().then(|| Law::Table {
        table: i,
        pressure: table.prescribed_pressure.unwrap_or(d.pressure),
        gap: d.penetration,
    })
}

/// The law of gap link `l`: its material pair's table at gap −g (open),
/// else the medium's k(T)/g + h_nf.
pub fn gap_law(model: &Model, gs: &crate::scenario::GapSpec, l: &GapLink) -> Law {
    let c = model.contact.as_ref().expect("gaps come with [contact]");
    let [a, b] = l.materials;
    match c.table[a as usize][b as usize] {
        Some(i) => Law::Table {
            table: i,
            pressure: 0.0,
            gap: -l.gap,
        },
        None => Law::Medium {
            gap: l.gap,
            h: gs.h,
        },
    }
}

/// The laws' tables: the scenario's, and the gap medium's k(T) (a
/// constant k as a one-point table).
pub fn laws(model: &Model) -> Laws {
    let Some(c) = model.contact.as_ref() else {
        return Laws::default();
    };
    let medium = c.gap.as_ref().map(|g| {
        g.conductivity_table
            .clone()
            .unwrap_or(crate::contact::table::Table1 {
                x: vec![0.0],
                y: vec![g.conductivity],
            })
    });
    Laws {
        tables: c.tables.clone(),
        medium,
    }
}

/// A pair's unit (Λ at unit conductance: the block at Rc = 1; T̄ the mean
/// of the two sides' face temperatures, eq 26's weights).
pub fn pair_unit(
    p: &crate::contact::ContactPair,
    d: &crate::contact::PairDofs,
    law: Law,
    block: fn(&crate::contact::ContactPair, f64) -> [f64; 64],
) -> Unit {
    let s = &p.surface;
    let (st, sc) = (
        s.w_target.iter().sum::<f64>(),
        s.w_contactor.iter().sum::<f64>(),
    );
    let mut mean = [0.0; 8];
    for i in 0..4 {
        mean[i] = 0.5 * s.w_target[i] / st;
        mean[4 + i] = 0.5 * s.w_contactor[i] / sc;
    }
    Unit {
        rows: d.petsc,
        n: 8,
        lap: block(p, 1.0),
        mean,
        law,
    }
}

/// A gap link's unit: Λ of [`add_links`] at conductance area A; T̄ the
/// mean of the searching face's corners and the point met.
pub fn gap_unit(l: &GapLink, law: Law) -> Unit {
    let mut rows = [0; 8];
    rows[..3].copy_from_slice(&l.rows_a);
    rows[3..6].copy_from_slice(&l.rows_b);
    let mut lap = [0.0; 64];
    let mut mean = [0.0; 8];
    for i in 0..3 {
        mean[i] = 1.0 / 6.0;
        mean[3 + i] = 0.5 * l.beta[i];
        for j in 0..3 {
            let c = l.area * l.beta[j] / 3.0;
            let (a, b) = (i, 3 + j);
            lap[8 * a + a] += c;
            lap[8 * b + b] += c;
            lap[8 * a + b] -= c;
            lap[8 * b + a] -= c;
        }
    }
    Unit {
        rows,
        n: 6,
        lap,
        mean,
        law,
    }
}

/// The rows of a gap link: the searching face's corners, then the facing face's.
fn gap_rows(l: &GapLink) -> [i32; 6] {
    let mut r = [0; 6];
    for j in 0..3 {
        r[j] = l.rows_a[j] as i32;
        r[3 + j] = l.rows_b[j] as i32;
    }
    r
}

/// Add the links of gap `l` with total conductance `g` to `m`: corner i of
/// the searching face to corner j of the facing one with g β_j / 3, so
/// the heat is g (mean T_a − T_b at the ray's point), and every row sums
/// to zero (heat is exchanged, not made).
fn add_links(m: &mut Matrix, l: &GapLink, g: f64) -> Result<()> {
    let idx = gap_rows(l);
    let mut block = [0.0; 36];
    for i in 0..3 {
        for j in 0..3 {
            let c = g * l.beta[j] / 3.0;
            let (a, b) = (i, 3 + j);
            block[6 * a + a] += c;
            block[6 * b + b] += c;
            block[6 * a + b] -= c;
            block[6 * b + a] -= c;
        }
    }
    m.add_values(&idx, &idx, &block)
}

/// Collective. Per owned PETSc row: the free area of the faces of bodies
/// that see the ambient, and the same weighted by emissivity. A node's
/// area is the third of each of its boundary faces' areas (lumped, as eq
/// 24 shares contact areas); the contact surface's share of it (S w of
/// each pair, eq 25) is taken off, so closed contacts do not exchange
/// with the ambient.
fn free_areas<'p>(
    petsc: &'p Petsc,
    model: &Model,
    part: &Part,
    contacts: &ContactSet,
    ambient: &crate::model::ambient::Ambient,
) -> Result<(Vector<'p>, Vector<'p>)> {
    let owned = part.owned_rows();
    let mut full = Vector::new(petsc, owned)?;
    full.set(0.0)?;
    let mut eps = full.duplicate()?;
    eps.set(0.0)?;
    let mut touching = full.duplicate()?;
    touching.set(0.0)?;
    let g = |l: u32| part.petsc[l as usize] as i32;
    for e in 0..part.num_elements() {
        if !ambient.body[part.mesh.body[e] as usize] || part.face_mask[e] == 0 {
            continue;
        }
        let tet = part.mesh.tets[e];
        let emissivity = model.materials[part.elem_material[e] as usize].emissivity;
        for (f, local) in crate::mesh::LOCAL_FACES.iter().enumerate() {
            if part.face_mask[e] & (1 << f) == 0 {
                continue;
            }
            let face = local.map(|i| tet[i]);
            let (area, _) =
                element::triangle_area_normal(&face.map(|n| part.mesh.nodes[n as usize]));
            full.set_values(&face.map(g), &[area / 3.0; 3], true)?;
            eps.set_values(&face.map(g), &[emissivity * area / 3.0; 3], true)?;
        }
    }
    for (p, d) in contacts.local.iter().zip(&contacts.dofs) {
        let rows = d.petsc.map(|n| n as i32);
        let mut v = [0.0; 8];
        for i in 0..4 {
            v[i] = p.surface.s_target * p.surface.w_target[i];
            v[4 + i] = p.surface.s_contactor * p.surface.w_contactor[i];
        }
        touching.set_values(&rows, &v, true)?;
    }
    // A face across a near-field gap sees the other body, not the ambient.
    for l in &contacts.gaps {
        let rows: Vec<i32> = l
            .rows_a
            .iter()
            .chain(&l.rows_b)
            .map(|&n| n as i32)
            .collect();
        let mut v = [l.area / 3.0; 6];
        for j in 0..3 {
            v[3 + j] = l.area * l.beta[j];
        }
        touching.set_values(&rows, &v, true)?;
    }
    full.assemble()?;
    eps.assemble()?;
    touching.assemble()?;
    {
        let t = touching.view()?;
        let mut ev = eps.view_mut()?;
        let mut fv = full.view_mut()?;
        for i in 0..fv.len() {
            let free = if fv[i] > 0.0 {
                (1.0 - t[i] / fv[i]).clamp(0.0, 1.0)
            } else {
                0.0
            };
            fv[i] *= free;
            ev[i] *= free;
        }
    }
    Ok((full, eps))
}

/// Per (target body, contactor body): Σ over pairs of g v_i per node (seed
/// 000 sec 5.2, exact form), nodes by PETSc number: rows of the
/// average-ΔT conductance.
fn average_rows(model: &Model, contacts: &ContactSet) -> BTreeMap<(u32, u32), BTreeMap<u32, f64>> {
    let mut rows: BTreeMap<(u32, u32), BTreeMap<u32, f64>> = Default::default();
    for (p, d) in contacts.local.iter().zip(&contacts.dofs) {
        let g = p.area() / pair_resistance(model, d, 0.0);
        let r = rows.entry((d.bodies[0], d.bodies[1])).or_default();
        for i in 0..4 {
            *r.entry(d.petsc[i]).or_default() += g * p.surface.w_target[i];
            *r.entry(d.petsc[4 + i]).or_default() -= g * p.surface.w_contactor[i];
        }
    }
    rows
}

/// Collective. Every node of each body in `bodies` (ascending): its PETSc
/// number and its share of its body's heat capacity, a_n = C_n / C_body,
/// gathered on every rank from the parts (the average-ΔT coupling reads
/// whole bodies; it serves the small validation models of seed 000 sec 5).
fn body_weights(
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    bodies: &[u32],
) -> BTreeMap<u32, Vec<(u32, f64)>> {
    let mut mine: Vec<f64> = Vec::new();
    for e in 0..part.num_elements() {
        let b = part.mesh.body[e];
        if bodies.binary_search(&b).is_err() {
            continue;
        }
        let m = &model.materials[part.elem_material[e] as usize];
        let c = m.density * m.specific_heat * part.mesh.element_volume(e) / 4.0;
        for &l in &part.mesh.tets[e] {
            mine.extend_from_slice(&[f64::from(b), f64::from(part.petsc[l as usize]), c]);
        }
    }
    let all = crate::parallel::all_gather_f64(comm, &mine);
    let mut cap: BTreeMap<u32, BTreeMap<u32, f64>> = Default::default();
    for r in all.chunks_exact(3) {
        *cap.entry(r[0] as u32)
            .or_default()
            .entry(r[1] as u32)
            .or_default() += r[2];
    }
    cap.into_iter()
        .map(|(b, nodes)| {
            let total: f64 = nodes.values().sum();
            (b, nodes.into_iter().map(|(n, c)| (n, c / total)).collect())
        })
        .collect()
}

/// Collective. Assemble M, K + H + Ch and f for this rank's part, with the
/// contact conductance of `contacts` (seed 000 eqs 24–30). The pattern is
/// the union of the element and contact blocks, preallocated exactly.
pub fn assemble<'p>(
    petsc: &'p Petsc,
    comm: &SimpleCommunicator,
    model: &Model,
    part: &Part,
    contacts: &ContactSet,
) -> crate::error::Result<Operators<'p>> {
    let mode = model.contact.as_ref().map_or(DeltaT::Local, |c| c.delta_t);
    let (block, block_row) = match model.contact.as_ref().map(|c| c.operator) {
        Some(ContactOperator::RankOne) => (
            rank_one_conductance_block as fn(&_, _) -> _,
            rank_one_conductance_row as fn(&_, _, _) -> _,
        ),
        _ => (local_conductance_block as _, local_conductance_row as _),
    };
    let owned = part.owned_rows();
    let g = |l: u32| part.petsc[l as usize] as i32;
    let elem_idx = |e: usize| part.mesh.tets[e].map(g);
    // The bonded particles' rows (issue 21).
    let particles = super::particles::ParticleHeat::new(model, part);
    // The average-ΔT rows, and the bodies' weights they couple to.
    let (rows, weights) = if mode == DeltaT::Average {
        let rows = average_rows(model, contacts);
        let mut wanted: Vec<u32> = rows.keys().flat_map(|&(a, b)| [a, b]).collect();
        let all = crate::parallel::all_gather_f64(
            comm,
            &wanted.iter().map(|&b| f64::from(b)).collect::<Vec<_>>(),
        );
        wanted = all.iter().map(|&b| b as u32).collect();
        wanted.sort_unstable();
        wanted.dedup();
        (rows, body_weights(comm, model, part, &wanted))
    } else {
        Default::default()
    };
    let average_cols = |a: u32, b: u32| -> (Vec<i32>, Vec<f64>) {
        let (wa, wb) = (&weights[&a], &weights[&b]);
        let cols = wa.iter().chain(wb).map(|&(n, _)| n as i32).collect();
        let vals = wa
            .iter()
            .map(|&(_, w)| w)
            .chain(wb.iter().map(|&(_, w)| -w))
            .collect();
        (cols, vals)
    };
    // The element blocks and the local-ΔT pairs' blocks go to PETSc row
    // by row (`row_sum`); the other terms are few and go block by block.
    let pair_rows = mode == DeltaT::Local;
    let pair_idx = |d: &crate::contact::PairDofs| d.petsc.map(|n| n as i32);
    // Hex8 bodies (issue 21): a hex's block at its first tet, none at its other five.
    let hexes = crate::parallel::PartHexes::new(model, part);
    let hex_of = |e: usize| {
        hexes
            .of_element
            .get(e)
            .filter(|&&h| h != crate::parallel::PartHexes::NONE)
            .map(|&h| &hexes.hexes[h as usize])
    };
    let elem_rows = |e: usize| -> ([i32; 8], usize) {
        let mut rows = [0; 8];
        match hex_of(e) {
            Some(h) if h.first as usize == e => (h.nodes.map(g), 8),
            Some(_) => (rows, 0),
            None => {
                rows[..4].copy_from_slice(&elem_idx(e));
                (rows, 4)
            }
        }
    };
    let inc = Incidence::new(
        (0..part.num_elements()).map(elem_rows),
        contacts.dofs[..if pair_rows { contacts.dofs.len() } else { 0 }]
            .iter()
            .map(pair_idx),
    );
    let mut row = RowSum::default();
    let pattern = |p: &mut crate::petsc::Pattern| -> Result<()> {
        for (r, items) in inc.rows() {
            row.clear();
            for item in items {
                let (cols, n) = match item {
                    Item::Element(e) => elem_rows(e),
                    Item::Pair(k) => (pair_idx(&contacts.dofs[k]), 8),
                };
                cols[..n].iter().for_each(|&c| row.add(c, 0.0, 0.0));
            }
            p.add(&[r], row.sorted().0)?;
        }
        particles.pattern(p)?;
        for (f, _, _) in &part.bc.convection {
            let idx = f.map(g);
            p.add(&idx, &idx)?;
        }
        for l in &contacts.gaps {
            let idx = gap_rows(l);
            p.add(&idx, &idx)?;
        }
        for (&(a, b), r) in &rows {
            let (cols, _) = average_cols(a, b);
            for &n in r.keys() {
                p.add(&[n as i32], &cols)?;
                p.add(&cols, &[n as i32])?;
            }
        }
        Ok(())
    };
    let mut capacity = Matrix::with_pattern(petsc, owned, pattern)?;
    let mut stiffness = capacity.duplicate()?;
    let mut load_flux = Vector::new(petsc, owned)?;
    let mut load_convection = Vector::new(petsc, owned)?;
    load_flux.set(0.0)?;
    load_convection.set(0.0)?;

    // Seed 000 eqs 14–16: the element conductivity and capacity blocks;
    // each row's sums go to PETSc with the local pairs' blocks (below).
    let element_blocks = |e: usize| {
        let mat = &model.materials[part.elem_material[e] as usize];
        let geo = crate::geometry::tet4_geometry(&part.mesh.element_coords(e));
        let k = element::conductivity(&geo, mat.conductivity);
        let rho_c = mat.density * mat.specific_heat;
        let m = match model.thermal.capacity {
            CapacityKind::Consistent => element::capacity_consistent(&geo, rho_c),
            CapacityKind::Lumped => element::capacity_lumped(&geo, rho_c),
        };
        (geo, k, m)
    };
    // The Hex8 counterparts (2×2×2 Gauss, `thermal::hex8`) of hex `h`.
    let hex_reference = |h: &crate::parallel::PartHex| {
        let x = h.nodes.map(|l| part.mesh.nodes[l as usize]);
        crate::mechanics::hex8_element::Hex8Gauss::from_coords(&x)
            .expect("a Hex8 body's hexes were checked when its mesh was made")
    };
    let hex_blocks = |e: usize, h: &crate::parallel::PartHex| {
        let mat = &model.materials[part.elem_material[e] as usize];
        let r = hex_reference(h);
        let rho_c = mat.density * mat.specific_heat;
        let m = match model.thermal.capacity {
            CapacityKind::Consistent => super::hex8::hex8_capacity_consistent(&r, rho_c),
            CapacityKind::Lumped => super::hex8::hex8_capacity_lumped(&r, rho_c),
        };
        (super::hex8::hex8_conductivity(&r, mat.conductivity), m)
    };
    for e in 0..part.num_elements() {
        let q = model.thermal.source[part.mesh.body[e] as usize];
        if q != 0.0 {
            match hex_of(e) {
                // ∫ N_I q dV of the hex, at its first tet.
                Some(h) if h.first as usize == e => {
                    let load = hex_reference(h).lumped_masses(q);
                    load_flux.set_values(&h.nodes.map(g), &load, true)?;
                }
                Some(_) => {}
                None => {
                    let geo = element_blocks(e).0;
                    load_flux.set_values(&elem_idx(e), &element::source_load(&geo, q), true)?;
                }
            }
        }
    }
    particles.add(&mut capacity, &mut stiffness, &mut load_flux)?;
    let coords = |f: &[u32; 3]| f.map(|n| part.mesh.nodes[n as usize]);
    for (f, q) in &part.bc.flux {
        let (area, _) = element::triangle_area_normal(&coords(f));
        load_flux.set_values(&f.map(g), &element::face_flux_load(area, *q), true)?;
    }
    for (f, h, tenv) in &part.bc.convection {
        let (area, _) = element::triangle_area_normal(&coords(f));
        let (hm, hl) = element::face_convection(area, *h, *tenv);
        let idx = f.map(g);
        stiffness.add_values(&idx, &idx, &hm)?;
        load_convection.set_values(&idx, &hl, true)?;
    }
    // Near-field gaps (seed 001 secs 7.1.4–7.1.5): conduction k/g and convection h
    // over the searching face's area, as links from its corners (a third
    // each) to the facing face's corners (the ray point's weights).
    // A law that follows the temperature makes the link a unit of the
    // nonlinear exchange instead.
    let gap_spec = model.contact.as_ref().and_then(|c| c.gap.as_ref());
    let laws = laws(model);
    let nonlinear = model
        .contact
        .as_ref()
        .is_some_and(|c| c.temperature_dependent());
    let mut units = Vec::new();
    if let Some(gs) = gap_spec {
        for l in &contacts.gaps {
            let law = gap_law(model, gs, l);
            if nonlinear && laws.depends_on_temperature(&law) {
                units.push(gap_unit(l, law));
                continue;
            }
            let h = laws.eval(&law, 0.0).0;
            if h > 0.0 {
                add_links(&mut stiffness, l, h * l.area)?;
            }
        }
    }
    // Free surfaces: lumped convection h a (T − T_env) and the radiation
    // coefficient ε σ a (seed 001 secs 7.1.2, 7.1.5–7.1.6; issue 20).
    let mut radiation = None;
    if let Some(amb) = model.thermal.ambient.as_ref() {
        let (area, eps) = free_areas(petsc, model, part, contacts, amb)?;
        let (lo, _) = area.ownership_range();
        if amb.h > 0.0 {
            let a = area.view()?;
            for (i, &ai) in a.iter().enumerate().filter(|(_, &ai)| ai > 0.0) {
                let r = (lo + i) as i32;
                stiffness.add_values(&[r], &[r], &[amb.h * ai])?;
                load_convection.set_values(&[r], &[amb.h * ai * amb.temperature], true)?;
            }
        }
        if amb.radiation {
            let mut coef = eps;
            coef.scale(super::radiation::STEFAN_BOLTZMANN)?;
            let offset = model.thermal.offset;
            radiation = Some(Radiation {
                coef,
                gap: None,
                offset,
                ambient4: (amb.temperature + offset).powi(4),
            });
        }
    }
    // Contact conductance (the capacity holds zeros there: one pattern).
    // Per local-ΔT pair its resistance, infinite where it adds no block.
    let mut rcs = Vec::new();
    if pair_rows {
        for (p, d) in contacts.local.iter().zip(&contacts.dofs) {
            if let Some(law) = pair_law(model, d) {
                units.push(pair_unit(p, d, law, block));
                rcs.push(f64::INFINITY);
            } else {
                rcs.push(pair_resistance(model, d, 0.0));
            }
        }
    }
    for (r, items) in inc.rows() {
        row.clear();
        for item in items {
            match item {
                Item::Element(e) => match hex_of(e) {
                    Some(h) => {
                        let (k, m) = hex_blocks(e, h);
                        let idx = h.nodes.map(g);
                        for a in (0..8).filter(|&a| idx[a] == r) {
                            for (b, &c) in idx.iter().enumerate() {
                                row.add(c, k[8 * a + b], m[8 * a + b]);
                            }
                        }
                    }
                    None => {
                        let (_, k, m) = element_blocks(e);
                        let idx = elem_idx(e);
                        for a in (0..4).filter(|&a| idx[a] == r) {
                            for (b, &c) in idx.iter().enumerate() {
                                row.add(c, k[4 * a + b], m[4 * a + b]);
                            }
                        }
                    }
                },
                Item::Pair(k) if rcs[k].is_finite() => {
                    let idx = pair_idx(&contacts.dofs[k]);
                    for a in (0..8).filter(|&a| idx[a] == r) {
                        let v = block_row(&contacts.local[k], rcs[k], a);
                        for (&c, &v) in idx.iter().zip(&v).filter(|(_, &v)| v != 0.0) {
                            row.add(c, v, 0.0);
                        }
                    }
                }
                Item::Pair(_) => {}
            }
        }
        let (cols, k, m) = row.sorted();
        stiffness.add_values(&[r], cols, k)?;
        capacity.add_values(&[r], cols, m)?;
    }
    // Average ΔT, row i: g v_i (a_A − a_B), a_X = node capacity / body capacity.
    for (&(a, b), r) in &rows {
        let (cols, a_vals) = average_cols(a, b);
        for (&n, &w) in r {
            let vals: Vec<f64> = a_vals.iter().map(|x| w * x).collect();
            stiffness.add_values(&[n as i32], &cols, &vals)?;
        }
    }
    capacity.assemble()?;
    stiffness.assemble()?;
    // Radiation across gaps: L in the operators' pattern.
    let mut gap_radiation = None;
    if let Some(gs) = gap_spec.filter(|g| g.radiation) {
        let mut lap = capacity.duplicate()?;
        lap.zero_entries()?;
        for l in &contacts.gaps {
            let [ea, eb] = l.materials.map(|m| model.materials[m as usize].emissivity);
            let vf = gs
                .view_factor_table
                .as_ref()
                .map_or(gs.view_factor, |t| t.eval(l.gap).0);
            let f = vf * super::radiation::grey_exchange(ea, eb);
            add_links(&mut lap, l, super::radiation::STEFAN_BOLTZMANN * f * l.area)?;
        }
        lap.assemble()?;
        gap_radiation = Some(lap);
    }
    if let Some(lap) = gap_radiation {
        let r = match radiation.take() {
            Some(r) => r,
            None => {
                let mut coef = Vector::new(petsc, owned)?;
                coef.set(0.0)?;
                Radiation {
                    coef,
                    gap: None,
                    offset: model.thermal.offset,
                    ambient4: 0.0,
                }
            }
        };
        radiation = Some(Radiation {
            gap: Some(lap),
            ..r
        });
    }
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
        radiation,
        exchange: nonlinear.then_some((units, laws)),
    })
}
