//! Explicit central-difference kernels of the finite-strain Tet4
//! mechanics (seed 004 sec 2; the time integration itself is not
//! written out in the seeds: standard explicit FDEM dynamics).
//!
//! The building blocks work on slices of elements and nodes and know
//! nothing about MPI, so a rank can run them on its owned elements and
//! local (owned + ghost) nodes and exchange the shared-node forces between
//! [`internal_forces`] and [`update_nodes`]:
//! - [`internal_forces`]: adds the element forces (seed 004 eqs 5–35 via
//!   [`element_response`]) into a nodal force array, records the stress,
//!   returns the strain energy.
//! - [`update_nodes`]: gravity, mass-proportional damping, velocity
//!   boundary conditions and the central-difference update.
//! - [`lumped_masses`], [`critical_dt`] / [`elements_critical_dt`],
//!   [`kinetic_energy`].
//!
//! [`crate::dynamics::ExplicitDomain`] ties them together, on one rank
//! or many.
//!
//! # Time integration
//! Central differences in leapfrog form (velocities live at half steps):
//! with f^n = f_int(x^n, v^{n−½}) + m g,
//! v^{n+½} = [(1 − c Δt/2) v^{n−½} + Δt f^n/m] / (1 + c Δt/2),
//! x^{n+1} = x^n + Δt v^{n+½}.
//! Mass-proportional damping −c m v is taken at the mid-point
//! (v^{n−½} + v^{n+½})/2, so it does not shorten the stable step; the
//! viscous stress 2 η D uses the lagged velocity v^{n−½}. With c = 0 this is
//! the symplectic (semi-implicit Euler / Störmer–Verlet) update.
//!
//! # Boundary conditions
//! Per node and component, `Some(u)` prescribes the velocity u (m/s):
//! `Some(0.0)` fixes the component; `None` leaves it free. Prescribed
//! components ignore forces.
//!
//! # Stable time step
//! Δt_crit = min over elements of (L/c)(√(1+ξ²) − ξ), with c the P-wave
//! speed, ξ the damping ratio the viscous stress gives the highest mode,
//! and L = (Σ_i |∇N_i|²)^(−1/2) = (Σ_i h_i⁻²)^(−1/2) a characteristic
//! length built from the four heights h_i of the tet
//! ([`element_critical_dt`], [`characteristic_length`](super::element::characteristic_length)). The smallest
//! height alone (= 3V / largest face area) is not safe: h_min/c exceeds the
//! true limit 2/ω_max of the lumped-mass Tet4 by up to 2× (by √2 for a
//! regular tet at ν = 0.2), whereas L/c is a rigorous small-strain bound and within 2×
//! of the limit (both checked by a unit test against the element
//! eigenvalues). The safety factor (default
//! [`DEFAULT_SAFETY`]) leaves margin for finite-strain stiffening and contact.

use nalgebra::{Matrix3, Vector3};

use super::element::{
    element_critical_dt, element_response, to_vectors, Tet4Reference, ThermalState,
};
use super::{ElasticMaterial, MechanicsError};
use crate::mesh::TetMesh;

/// Default ratio of the allowed time step to [`critical_dt`].
pub const DEFAULT_SAFETY: f64 = 0.8;

/// Velocity boundary condition of one node: per component, `Some(u)`
/// prescribes the velocity u (m/s, `Some(0.0)` = fixed), `None` = free.
pub type VelocityBc = [Option<f64>; 3];

/// One element of the explicit mechanics: its nodes (indices into the node
/// arrays the kernels get), reference data and material index.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MechElement {
    /// Node indices (positively oriented, as in [`TetMesh::tets`]).
    pub nodes: [u32; 4],
    /// Reference geometry.
    pub reference: Tet4Reference,
    /// Index into the material slice.
    pub material: u32,
}

/// The material of a tet that is one of a Hex8's six (issue 21): the
/// Tet4 kernels skip it; its hex's kernel fills its slots.
pub const HEX_TET: u32 = u32::MAX;

/// Builds the elements of `mesh`, material index = body id. Errors if a
/// body id has no material or an element is inverted or degenerate.
pub fn mesh_elements(
    mesh: &TetMesh,
    num_materials: usize,
) -> Result<Vec<MechElement>, MechanicsError> {
    if mesh.body.len() != mesh.tets.len() {
        return Err(MechanicsError::SizeMismatch {
            what: "mesh body ids",
            got: mesh.body.len(),
            expected: mesh.tets.len(),
        });
    }
    let mut out = Vec::with_capacity(mesh.tets.len());
    for (e, (&nodes, &body)) in mesh.tets.iter().zip(&mesh.body).enumerate() {
        if body as usize >= num_materials {
            return Err(MechanicsError::SizeMismatch {
                what: "materials (indexed by body id)",
                got: num_materials,
                expected: body as usize + 1,
            });
        }
        for &n in &nodes {
            if n as usize >= mesh.nodes.len() {
                return Err(MechanicsError::SizeMismatch {
                    what: "node index of an element",
                    got: n as usize,
                    expected: mesh.nodes.len(),
                });
            }
        }
        let reference =
            Tet4Reference::from_coords(&mesh.element_coords(e)).map_err(|err| err.at_element(e))?;
        out.push(MechElement {
            nodes,
            reference,
            material: body,
        });
    }
    Ok(out)
}

/// Temperatures driving the thermal expansion, one value per element of
/// the slice given to [`internal_forces`]: ΔT = element temperature −
/// reference (stress-free) temperature, and optionally Ṫ (K/s) for the
/// viscous stress. `None` means 0 everywhere.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ThermalLoad<'a> {
    /// ΔT per element (K).
    pub delta_t: Option<&'a [f64]>,
    /// Ṫ per element (K/s).
    pub rate: Option<&'a [f64]>,
}

impl<'a> ThermalLoad<'a> {
    /// Isothermal: no expansion.
    pub fn none() -> Self {
        Self::default()
    }

    /// Temperature changes without rates.
    pub fn steady(delta_t: &'a [f64]) -> Self {
        Self {
            delta_t: Some(delta_t),
            rate: None,
        }
    }

    /// Temperature changes and their rates.
    pub fn transient(delta_t: &'a [f64], rate: &'a [f64]) -> Self {
        Self {
            delta_t: Some(delta_t),
            rate: Some(rate),
        }
    }

    fn check(&self, num_elems: usize) -> Result<(), MechanicsError> {
        for (what, s) in [
            ("element temperature changes", self.delta_t),
            ("element temperature rates", self.rate),
        ] {
            if let Some(s) = s {
                if s.len() != num_elems {
                    return Err(MechanicsError::SizeMismatch {
                        what,
                        got: s.len(),
                        expected: num_elems,
                    });
                }
            }
        }
        Ok(())
    }

    fn at(&self, e: usize) -> ThermalState {
        ThermalState {
            delta_t: self.delta_t.map_or(0.0, |s| s[e]),
            rate: self.rate.map_or(0.0, |s| s[e]),
        }
    }
}

fn check_len(what: &'static str, got: usize, expected: usize) -> Result<(), MechanicsError> {
    if got == expected {
        Ok(())
    } else {
        Err(MechanicsError::SizeMismatch {
            what,
            got,
            expected,
        })
    }
}

/// The material of `el`, checking its material index and node indices
/// against `materials` and the `n` nodes.
fn checked_material<'m>(
    el: &MechElement,
    materials: &'m [ElasticMaterial],
    n: usize,
) -> Result<&'m ElasticMaterial, MechanicsError> {
    if let Some(&bad) = el.nodes.iter().find(|&&i| i as usize >= n) {
        return Err(MechanicsError::SizeMismatch {
            what: "node index of an element",
            got: bad as usize,
            expected: n,
        });
    }
    materials
        .get(el.material as usize)
        .ok_or(MechanicsError::SizeMismatch {
            what: "materials",
            got: materials.len(),
            expected: el.material as usize + 1,
        })
}

/// Adds the internal forces of `elements` at positions `x` and velocities
/// `v` into `forces` (not zeroed first, so several element blocks can
/// accumulate into one array), writes each element's Cauchy stress into
/// `stress` if given, and returns the total stored strain energy (J).
///
/// `x`, `v` and `forces` are indexed by the elements' node indices;
/// `thermal` and `stress` by position in `elements`. Errors on mismatched
/// lengths, out-of-range indices and inverted elements (the element index
/// in the error is the position in `elements`).
pub fn internal_forces(
    elements: &[MechElement],
    materials: &[ElasticMaterial],
    x: &[Vector3<f64>],
    v: &[Vector3<f64>],
    thermal: ThermalLoad<'_>,
    forces: &mut [Vector3<f64>],
    stress: Option<&mut [Matrix3<f64>]>,
) -> Result<f64, MechanicsError> {
    check_len("forces", forces.len(), x.len())?;
    let forces = &mut forces[..x.len()];
    for_each_element(elements, materials, x, v, thermal, stress, |_, idx, f| {
        for (f, &i) in f.iter().zip(&idx) {
            forces[i] += f;
        }
    })
}

/// The loop shared by [`internal_forces`] and [`element_forces`]: the
/// fast kernel per element (the reference [`element_response`] for the
/// rare element it declines), stresses recorded, and `sink(e, nodes,
/// forces)` given each element's four nodal forces. Returns the strain
/// energy.
#[inline(always)]
fn for_each_element(
    elements: &[MechElement],
    materials: &[ElasticMaterial],
    x: &[Vector3<f64>],
    v: &[Vector3<f64>],
    thermal: ThermalLoad<'_>,
    mut stress: Option<&mut [Matrix3<f64>]>,
    mut sink: impl FnMut(usize, [usize; 4], &[Vector3<f64>; 4]),
) -> Result<f64, MechanicsError> {
    use super::element::{tet4_forces, KernelMaterial};
    let n = x.len();
    check_len("velocities", v.len(), n)?;
    thermal.check(elements.len())?;
    if let Some(s) = stress.as_deref() {
        check_len("element stresses", s.len(), elements.len())?;
    }
    // Equal lengths, so one `i < n` test below covers both arrays.
    let v = &v[..n];
    // Lamé constants etc. once per material, not per element.
    let constants: Vec<KernelMaterial> = materials.iter().map(KernelMaterial::new).collect();
    let mut energy = 0.0;
    for (e, el) in elements.iter().enumerate() {
        if el.material == HEX_TET {
            // A Hex8's tet: its hex's kernel fills its slots (issue 21).
            continue;
        }
        let idx = el.nodes.map(|i| i as usize);
        let material = match constants.get(el.material as usize) {
            Some(m) if idx.iter().all(|&i| i < n) => m,
            _ => return Err(index_error(el, materials, n)),
        };
        let th = thermal.at(e);
        let r = match tet4_forces(&el.reference, material, x, v, idx, th) {
            Some(r) => r,
            None => declined_response(el, &materials[el.material as usize], x, v, th)
                .map_err(|err| err.at_element(e))?,
        };
        sink(e, idx, &r.forces);
        if let Some(s) = stress.as_deref_mut() {
            s[e] = r.stress;
        }
        energy += r.strain_energy;
    }
    Ok(energy)
}

/// The error of an element whose node or material index is out of range
/// (kept out of the hot loop of [`internal_forces`]).
#[cold]
#[inline(never)]
fn index_error(el: &MechElement, materials: &[ElasticMaterial], n: usize) -> MechanicsError {
    match checked_material(el, materials, n) {
        Err(err) => err,
        Ok(_) => unreachable!("index_error called on an element with valid indices"),
    }
}

/// [`element_response`] of an element the fast kernel declined (J or
/// 1 + α ΔT not positive): its error, or its response should round-off
/// let the reference path accept the element.
#[cold]
#[inline(never)]
fn declined_response(
    el: &MechElement,
    material: &ElasticMaterial,
    x: &[Vector3<f64>],
    v: &[Vector3<f64>],
    thermal: ThermalState,
) -> Result<super::element::Tet4Forces, MechanicsError> {
    let (xe, ve) = (
        el.nodes.map(|i| x[i as usize]),
        el.nodes.map(|i| v[i as usize]),
    );
    element_response(&el.reference, material, &xe, &ve, thermal).map(Into::into)
}

/// As [`internal_forces`], but writes each element's four nodal forces
/// into `out[e]` instead of adding them into a nodal array, so that a
/// caller can sum them in an order of its choosing (the parallel driver
/// sums in global element order, which makes the result independent of
/// the partition).
pub fn element_forces(
    elements: &[MechElement],
    materials: &[ElasticMaterial],
    x: &[Vector3<f64>],
    v: &[Vector3<f64>],
    thermal: ThermalLoad<'_>,
    out: &mut [[Vector3<f64>; 4]],
    stress: Option<&mut [Matrix3<f64>]>,
) -> Result<f64, MechanicsError> {
    check_len("element forces", out.len(), elements.len())?;
    for_each_element(elements, materials, x, v, thermal, stress, |e, _, f| {
        out[e] = *f;
    })
}

/// Lumped nodal masses: ρ V0 / 4 of every element on each of its nodes.
pub fn lumped_masses(
    elements: &[MechElement],
    materials: &[ElasticMaterial],
    num_nodes: usize,
) -> Result<Vec<f64>, MechanicsError> {
    let mut m = vec![0.0; num_nodes];
    for el in elements {
        let mat = materials
            .get(el.material as usize)
            .ok_or(MechanicsError::SizeMismatch {
                what: "materials",
                got: materials.len(),
                expected: el.material as usize + 1,
            })?;
        // Not numbered in the seeds: row-sum lumped mass ρ V0/4 per node of a Tet4.
        let share = mat.density * el.reference.volume0 / 4.0;
        for &i in &el.nodes {
            *m.get_mut(i as usize).ok_or(MechanicsError::SizeMismatch {
                what: "node index of an element",
                got: i as usize,
                expected: num_nodes,
            })? += share;
        }
    }
    Ok(m)
}

/// Parameters of one node update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeUpdate {
    /// Time step Δt (s).
    pub dt: f64,
    /// Gravitational acceleration (m/s²).
    pub gravity: Vector3<f64>,
    /// Mass-proportional damping coefficient c (1/s): force −c m v.
    pub mass_damping: f64,
}

/// Central-difference update of the nodes (see the module docs):
/// `v` holds v^{n−½} on entry and v^{n+½} on return, `x` advances from x^n
/// to x^{n+1}; `force` is the total internal + external force at step n
/// (gravity is added here). Nodes with zero mass (in no element) keep their
/// velocity unless prescribed. Errors on mismatched lengths or a non-finite
/// result.
pub fn update_nodes(
    p: &NodeUpdate,
    mass: &[f64],
    force: &[Vector3<f64>],
    bc: &[VelocityBc],
    x: &mut [Vector3<f64>],
    v: &mut [Vector3<f64>],
) -> Result<(), MechanicsError> {
    update_nodes_damped(p, |_| p.mass_damping, mass, force, None, bc, x, v).map(|_| ())
}

/// What the loads and the damping did to the nodes in one update (J).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NodeWork {
    /// Work of the external loads (the `ext` part of the force, gravity)
    /// and of the prescribed velocities' reactions.
    pub external: f64,
    /// Energy taken by the mass damping.
    pub damping: f64,
}

/// [`update_nodes`] with node `i` damped by `damping(i)` (1/s) instead of
/// `p.mass_damping` (a packing stage damps the bodies in contact and
/// lets the others fall freely), and the work of the loads: `ext` is the
/// external part of `force` (tractions; None: all of it is internal).
///
/// With v̄ = (v^{n−½} + v^{n+½})/2 the velocity at step n, the loads do
/// (f_ext + m g)·v̄ Δt on a free component, and a prescribed component's
/// reaction R = m (v^{n+½} − v^{n−½})/Δt − f^n − m g adds R·v̄ Δt; the
/// damping takes c m |v̄|² Δt from the free components. Then the kinetic
/// energy's change is the work of all forces minus the damping's, exactly
/// for this update, which is what the energy balance checks.
#[allow(clippy::too_many_arguments)]
pub fn update_nodes_damped(
    p: &NodeUpdate,
    damping: impl Fn(usize) -> f64,
    mass: &[f64],
    force: &[Vector3<f64>],
    ext: Option<&[Vector3<f64>]>,
    bc: &[VelocityBc],
    x: &mut [Vector3<f64>],
    v: &mut [Vector3<f64>],
) -> Result<NodeWork, MechanicsError> {
    let n = x.len();
    check_len("velocities", v.len(), n)?;
    check_len("masses", mass.len(), n)?;
    check_len("forces", force.len(), n)?;
    check_len("velocity boundary conditions", bc.len(), n)?;
    if let Some(e) = ext {
        check_len("external forces", e.len(), n)?;
    }
    // Summed in locals (registers), in node order.
    let (mut external, mut damped) = (0.0, 0.0);
    // The two divisions of the damped update depend on c alone: made again
    // only when c changes from one node to the next (a run has one or two
    // values), the same numbers as made per node.
    let factors = |c: f64| {
        let half = 0.5 * c * p.dt;
        ((1.0 - half) / (1.0 + half), p.dt / (1.0 + half))
    };
    let mut last_c = p.mass_damping;
    let (mut keep, mut scale) = factors(last_c);
    for i in 0..n {
        let v_old = v[i];
        let mut vi = v_old;
        let c = damping(i);
        if c.to_bits() != last_c.to_bits() {
            last_c = c;
            (keep, scale) = factors(c);
        }
        if mass[i] > 0.0 {
            let a = force[i] / mass[i] + p.gravity;
            // Not numbered in the seeds: central difference with mid-point damping, v^{n+½} = ((1 − cΔt/2) v^{n−½} + Δt a^n)/(1 + cΔt/2).
            vi = vi * keep + a * scale;
        }
        for d in 0..3 {
            if let Some(u) = bc[i][d] {
                vi[d] = u;
            }
        }
        if mass[i] > 0.0 {
            let load = ext.map_or(Vector3::zeros(), |e| e[i]) + p.gravity * mass[i];
            // The node's sums first, then the totals: no long chain of
            // additions through one accumulator.
            let (mut work_i, mut free_v2) = (0.0, 0.0);
            for d in 0..3 {
                let mean = 0.5 * (v_old[d] + vi[d]);
                if bc[i][d].is_some() {
                    // The reaction's work: m Δv − Δt (f + m g), on v̄.
                    let r = mass[i] * (vi[d] - v_old[d])
                        - p.dt * (force[i][d] + p.gravity[d] * mass[i]);
                    work_i += (r + p.dt * load[d]) * mean;
                } else {
                    work_i += p.dt * load[d] * mean;
                    free_v2 += mean * mean;
                }
            }
            external += work_i;
            damped += p.dt * c * mass[i] * free_v2;
        }
        // Not numbered in the seeds: x^{n+1} = x^n + Δt v^{n+½}.
        let xi = x[i] + vi * p.dt;
        if !(xi.iter().all(|c| c.is_finite()) && vi.iter().all(|c| c.is_finite())) {
            return Err(MechanicsError::NonFinite { node: i });
        }
        v[i] = vi;
        x[i] = xi;
    }
    Ok(NodeWork {
        external,
        damping: damped,
    })
}

/// Kinetic energy ½ Σ m |v|² (J).
pub fn kinetic_energy(mass: &[f64], v: &[Vector3<f64>]) -> f64 {
    0.5 * mass
        .iter()
        .zip(v)
        .map(|(m, v)| m * v.norm_squared())
        .sum::<f64>()
}

/// The critical time step and the element that sets it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CriticalDt {
    /// Δt_crit (s); infinite for an empty element set.
    pub dt: f64,
    /// Index of the limiting element.
    pub elem: usize,
}

/// Critical time step of `elements` at positions `x` (the reference
/// positions for an estimate made once, current ones to re-check during
/// large deformation): min over elements of [`element_critical_dt`].
pub fn elements_critical_dt(
    elements: &[MechElement],
    materials: &[ElasticMaterial],
    x: &[Vector3<f64>],
) -> Result<CriticalDt, MechanicsError> {
    let mut best = CriticalDt {
        dt: f64::INFINITY,
        elem: 0,
    };
    for (e, el) in elements.iter().enumerate() {
        let mat = checked_material(el, materials, x.len())?;
        let dt = element_critical_dt(&el.nodes.map(|i| x[i as usize]), mat);
        if dt < best.dt {
            best = CriticalDt { dt, elem: e };
        }
    }
    Ok(best)
}

/// Critical time step of `mesh` (reference coordinates), with
/// `materials[mesh.body[e]]` the material of element `e`.
pub fn critical_dt(
    mesh: &TetMesh,
    materials: &[ElasticMaterial],
) -> Result<CriticalDt, MechanicsError> {
    let mut best = CriticalDt {
        dt: f64::INFINITY,
        elem: 0,
    };
    check_len("mesh body ids", mesh.body.len(), mesh.tets.len())?;
    for e in 0..mesh.tets.len() {
        let body = mesh.body[e] as usize;
        let mat = materials.get(body).ok_or(MechanicsError::SizeMismatch {
            what: "materials (indexed by body id)",
            got: materials.len(),
            expected: body + 1,
        })?;
        let dt = element_critical_dt(&to_vectors(&mesh.element_coords(e)), mat);
        if dt < best.dt {
            best = CriticalDt { dt, elem: e };
        }
    }
    Ok(best)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::box_mesh;

    fn concrete(alpha: f64) -> ElasticMaterial {
        // Seed 004 Table 1 (E, ν); density not in the table (concrete, 2400 kg/m³).
        ElasticMaterial {
            young: 20e9,
            poisson: 0.2,
            density: 2400.0,
            expansion: alpha,
            viscosity: 0.0,
        }
    }

    /// The element bound of the stable step: Kuhn tets of edge 0.5 have
    /// L = 0.5/√6, so Δt_crit = L/c (round-off tolerance), the same over
    /// the mesh as over its elements.
    #[test]
    fn critical_dt_of_kuhn_tets() {
        let mat = concrete(1e-5);
        let mesh = box_mesh([0.0; 3], [1.0; 3], 0.5).unwrap();
        let crit = critical_dt(&mesh, &[mat]).unwrap();
        let want = 0.5 / 6f64.sqrt() / mat.p_wave_speed();
        assert!((crit.dt / want - 1.0).abs() < 1e-12);
        let elements = mesh_elements(&mesh, 1).unwrap();
        let x: Vec<Vector3<f64>> = mesh.nodes.iter().map(|p| Vector3::from(*p)).collect();
        assert_eq!(elements_critical_dt(&elements, &[mat], &x).unwrap(), crit);
        assert!(matches!(
            critical_dt(&mesh, &[]),
            Err(MechanicsError::SizeMismatch { .. })
        ));
    }

    /// Per-rank use: forces of two element blocks accumulated into one
    /// array equal the forces of all elements at once (round-off), and the
    /// masses add up the same way.
    #[test]
    fn element_blocks_accumulate() {
        let mat = concrete(1e-5);
        let mesh = box_mesh([0.0; 3], [1.0; 3], 0.5).unwrap();
        let elements = mesh_elements(&mesh, 1).unwrap();
        let n = mesh.nodes.len();
        let x: Vec<Vector3<f64>> = mesh
            .nodes
            .iter()
            .map(|p| {
                let p = Vector3::from(*p);
                p + Vector3::new(0.01 * p.y * p.z, -0.02 * p.x, 0.015 * p.x * p.y)
            })
            .collect();
        let v: Vec<Vector3<f64>> = x.iter().map(|p| Vector3::new(p.z, 0.0, -p.x)).collect();
        let dt_e: Vec<f64> = (0..elements.len()).map(|e| e as f64).collect();
        let mut all = vec![Vector3::zeros(); n];
        let w_all = internal_forces(
            &elements,
            &[mat],
            &x,
            &v,
            ThermalLoad::steady(&dt_e),
            &mut all,
            None,
        )
        .unwrap();
        let half = elements.len() / 2;
        let mut parts = vec![Vector3::zeros(); n];
        let mut w = 0.0;
        for (blk, temps) in [
            (&elements[..half], &dt_e[..half]),
            (&elements[half..], &dt_e[half..]),
        ] {
            w += internal_forces(
                blk,
                &[mat],
                &x,
                &v,
                ThermalLoad::steady(temps),
                &mut parts,
                None,
            )
            .unwrap();
        }
        let fmax = all.iter().map(|f| f.norm()).fold(0.0, f64::max);
        for i in 0..n {
            assert!((all[i] - parts[i]).norm() < 1e-12 * fmax);
        }
        assert!((w - w_all).abs() < 1e-12 * w_all);
        let m = lumped_masses(&elements, &[mat], n).unwrap();
        assert!((m.iter().sum::<f64>() - 2400.0).abs() < 1e-9);
    }

    /// Per-node damping: an undamped node falls freely (v = g t, x = ½ g t²
    /// up to the half-step offset), a damped one tends to v = g / c.
    #[test]
    fn per_node_damping_free_fall_and_terminal_speed() {
        let g = Vector3::new(0.0, 0.0, -9.81);
        let (dt, c) = (1e-3, 10.0);
        let p = NodeUpdate {
            dt,
            gravity: g,
            mass_damping: c,
        };
        let mass = [1.0, 1.0];
        let force = [Vector3::zeros(); 2];
        let bc = [[None; 3]; 2];
        let mut x = [Vector3::zeros(); 2];
        let mut v = [Vector3::zeros(); 2];
        let n = 2000;
        for _ in 0..n {
            let damping = |i: usize| if i == 0 { 0.0 } else { c };
            update_nodes_damped(&p, damping, &mass, &force, None, &bc, &mut x, &mut v).unwrap();
        }
        let t = n as f64 * dt;
        // Not numbered in the seeds: explicit free fall, v = g t, x = g Δt² n(n+1)/2.
        assert!((v[0] - g * t).norm() < 1e-9 * g.norm() * t);
        let x_want = g * dt * dt * (n * (n + 1)) as f64 / 2.0;
        assert!((x[0] - x_want).norm() < 1e-9 * x_want.norm());
        // Terminal speed g / c after 20 time constants.
        assert!((v[1] - g / c).norm() < 1e-6, "{:?}", v[1]);
        // The uniform update is the per-node one with c everywhere.
        let (mut xa, mut va) = ([Vector3::zeros(); 2], [Vector3::new(1.0, 2.0, 3.0); 2]);
        let (mut xb, mut vb) = (xa, va);
        update_nodes(&p, &mass, &force, &bc, &mut xa, &mut va).unwrap();
        update_nodes_damped(&p, |_| c, &mass, &force, None, &bc, &mut xb, &mut vb).unwrap();
        assert_eq!((xa, va), (xb, vb));
    }
}
