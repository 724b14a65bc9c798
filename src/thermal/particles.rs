//! The bonded particles of a rank's bodies as rows of the one thermal
//! system (issue 21, seed 002): each sphere carries a temperature, the
//! last rows of the rank's range ([`Part::first_particle_row`]), with the
//! capacity ρ c (2r)³ of its cell, the bonds between spheres and the links
//! to the elements as conduction blocks ([`super::lattice_heat`]), and the
//! body's volumetric source over its cell. A sphere's row is its owner's
//! (`parallel::spheres`); a bond is assembled by the owner of its first
//! end, a link by the rank holding its element, into the one matrix
//! (a ghost sphere's row may be another rank's); the blocks enter the same
//! K and M as the elements', and the θ method and the energy account treat
//! them alike.

use crate::mechanics::bond::bond_conductance;
use crate::model::Model;
use crate::model::ThermalKind;
use crate::parallel::Part;
use crate::petsc::{Matrix, Pattern, Result, Vector};

use super::lattice_heat::{bond_block, link_block};

/// A link's rows: the sphere's, the element's four nodes', N_I at the
/// bond's midpoint and the half bond's conductance.
#[derive(Debug, Clone)]
struct LinkRows {
    sphere: i32,
    nodes: [i32; 4],
    shape: [f64; 4],
    g: f64,
}

/// One body's particles on this rank.
#[derive(Debug, Clone)]
pub struct BodyHeat {
    /// Global number of its first particle (the output's rows).
    pub first_gid: u64,
    /// The owned spheres (numbers in the body, ascending).
    pub owned: Vec<u32>,
    /// PETSc row of its first owned particle (the others follow).
    pub first_row: usize,
    /// Reference centres (m) of the owned spheres.
    pub centres: Vec<[f64; 3]>,
    /// Initial temperature of each owned sphere: the body's, or that of
    /// the last `thermal.initial` whose set holds the sphere.
    pub initial: Vec<f64>,
    /// Heat capacity of each sphere's cell, ρ c (2r)³ (J/K).
    capacity: f64,
    /// Source of each sphere's cell, q (2r)³ (W).
    source: f64,
    /// Bonds: rows and conductance h w (W/K).
    bonds: Vec<(i32, i32, f64)>,
    links: Vec<LinkRows>,
}

/// The particles of the bodies a rank holds, in ascending body id.
#[derive(Debug, Clone, Default)]
pub struct ParticleHeat {
    pub bodies: Vec<BodyHeat>,
}

impl ParticleHeat {
    /// The particle rows of `part` (empty without heat or particles; a
    /// rank without spheres of its own may assemble heat links).
    pub fn new(model: &Model, part: &Part) -> ParticleHeat {
        if !model.thermal_active || part.spheres.is_empty() {
            return ParticleHeat::default();
        }
        let (offsets, _) = model.particle_offsets();
        let mut row = part.first_particle_row();
        let mut bodies = Vec::new();
        for held in &part.spheres {
            let b = held.body as usize;
            let body = &model.bodies[b];
            let p = model
                .body_particles(body)
                .expect("spheres of a body with particles");
            let region = &p.region;
            let mat = &model.materials[p.material as usize];
            let cell = (2.0 * region.radius).powi(3);
            let h = bond_conductance(mat.conductivity, region.radius);
            let n_owned = held.owned.len();
            // Each sphere's row: owned ones from `row` on, ghosts their owners'.
            let row_of = |s: u32| -> i32 {
                match held.owned.binary_search(&s) {
                    Ok(k) => (row + k) as i32,
                    Err(_) => {
                        let k = held.ghosts.binary_search(&s).expect("a ghost sphere");
                        part.ghost_sphere_row(held, k) as i32
                    }
                }
            };
            let node_rows = |src_elem: u32| -> [i32; 4] {
                let e = part
                    .elem_gid
                    .binary_search(&(body.elem_range.0 + src_elem))
                    .expect("a heat link's element is here");
                part.mesh.tets[e].map(|l| part.petsc[l as usize] as i32)
            };
            let bonds = held
                .bonds
                .iter()
                .map(|&k| &region.bonds[k as usize])
                .filter(|bd| held.owned.binary_search(&bd.i).is_ok())
                .map(|bd| {
                    let g = h[bd.kind as usize] * bd.weight;
                    (row_of(bd.i), row_of(bd.j), g)
                })
                .collect();
            // The half bonds for heat (mesh::heat_links): the links and the outward edge ones.
            let links = held
                .heat_links
                .iter()
                .map(|&k| {
                    let l = &region.heat_links[k as usize];
                    LinkRows {
                        sphere: row_of(l.sphere),
                        nodes: node_rows(l.point_elem),
                        shape: l.point_shape,
                        // The half bond: its weight is already twice the lattice's.
                        g: h[l.kind as usize] * l.weight,
                    }
                })
                .collect();
            bodies.push(BodyHeat {
                first_gid: offsets[b],
                owned: held.owned.clone(),
                first_row: row,
                centres: held
                    .owned
                    .iter()
                    .map(|&s| region.centres[s as usize])
                    .collect(),
                initial: initial_of(model, b, &p.sphere_sets, &held.owned),
                // seed 002's particle as its cell (mechanics::bond docs): capacity ρ c (2r)³.
                capacity: mat.density * mat.specific_heat * cell,
                source: model.thermal.source[b] * cell,
                bonds,
                links,
            });
            row += n_owned;
        }
        ParticleHeat { bodies }
    }

    /// Adds the bonds' and links' blocks to the pattern.
    pub fn pattern(&self, p: &mut Pattern) -> Result<()> {
        for b in &self.bodies {
            for &(i, j, _) in &b.bonds {
                p.add(&[i, j], &[i, j])?;
            }
            for l in &b.links {
                let idx = link_rows(l);
                p.add(&idx, &idx)?;
            }
            for k in 0..b.centres.len() {
                let r = (b.first_row + k) as i32;
                p.add(&[r], &[r])?;
            }
        }
        Ok(())
    }

    /// Adds the particles' capacities to `capacity`, their conduction to
    /// `stiffness` and their sources to `load`.
    pub fn add(
        &self,
        capacity: &mut Matrix,
        stiffness: &mut Matrix,
        load: &mut Vector,
    ) -> Result<()> {
        for b in &self.bodies {
            for k in 0..b.centres.len() {
                let r = (b.first_row + k) as i32;
                capacity.add_values(&[r], &[r], &[b.capacity])?;
                if b.source != 0.0 {
                    load.set_values(&[r], &[b.source], true)?;
                }
            }
            for &(i, j, g) in &b.bonds {
                stiffness.add_values(&[i, j], &[i, j], &bond_block(g))?;
            }
            for l in &b.links {
                let idx = link_rows(l);
                stiffness.add_values(&idx, &idx, &link_block(l.g, &l.shape))?;
            }
        }
        Ok(())
    }

    /// This rank's particles for the output: global numbers, reference
    /// centres (flat, 3 each) and temperatures from the owned rows `rows`
    /// of `part` (none without them).
    pub fn rows(&self, part: &Part, rows: Option<&[f64]>) -> (Vec<u64>, Vec<f64>, Vec<f64>) {
        let lo = part.owned_range().0;
        let mut gid = Vec::new();
        let mut centres = Vec::new();
        let mut t = Vec::new();
        for b in &self.bodies {
            for (k, c) in b.centres.iter().enumerate() {
                gid.push(b.first_gid + u64::from(b.owned[k]));
                centres.extend_from_slice(c);
                if let Some(r) = rows {
                    t.push(r[b.first_row + k - lo]);
                }
            }
        }
        (gid, centres, t)
    }
}

/// The initial temperatures of body `b`'s spheres `owned` (ascending):
/// the body's, then each `thermal.initial` on a set of `sets` holding
/// some of them, in the scenario's order (as for nodes).
fn initial_of(
    model: &Model,
    b: usize,
    sets: &std::collections::BTreeMap<String, Vec<u32>>,
    owned: &[u32],
) -> Vec<f64> {
    let mut t = vec![model.bodies[b].initial_temperature; owned.len()];
    for (target, kind) in &model.thermal.bcs {
        let (ThermalKind::Initial(v), true) = (kind, target.body as usize == b) else {
            continue;
        };
        for s in sets.get(&target.set).into_iter().flatten() {
            if let Ok(k) = owned.binary_search(s) {
                t[k] = *v;
            }
        }
    }
    t
}

fn link_rows(l: &LinkRows) -> [i32; 5] {
    [l.sphere, l.nodes[0], l.nodes[1], l.nodes[2], l.nodes[3]]
}

/// The owned rows' start temperatures: the nodes' initial values, each
/// particle at its body's initial temperature.
pub fn initial_rows(model: &Model, part: &Part) -> Vec<f64> {
    let mut rows = part.nodes_to_rows(&part.bc.initial_t[..part.num_owned()]);
    let lo = part.owned_range().0;
    for b in &ParticleHeat::new(model, part).bodies {
        for k in 0..b.centres.len() {
            rows[b.first_row + k - lo] = b.initial[k];
        }
    }
    rows
}

/// The owned rows from the nodes' temperatures `nodes` (part order) and
/// the particles' rows of `old` (a previous numbering's owned rows: the
/// particle rows end both ranges).
pub fn rows_keeping_particles(part: &Part, nodes: &[f64], old: &[f64]) -> Vec<f64> {
    let mut rows = part.nodes_to_rows(nodes);
    let k = part.particle_rows;
    let (n, m) = (rows.len(), old.len());
    rows[n - k..].copy_from_slice(&old[m - k..]);
    rows
}
