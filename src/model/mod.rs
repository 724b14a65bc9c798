//! The data model every stage shares, of the size of the number of bodies: materials,
//! bodies (each with where its mesh comes from), the meshes bodies are made from (a body's
//! own mesh, or a template its copies share), and the boundary conditions resolved to a
//! body and a named set. Built from a scenario; holds no MPI or PETSc state. No rank builds
//! the mesh of every body: each makes the bodies it holds ([`crate::parallel::Part::build`]);
//! [`Model::whole_mesh`] makes them all on one process for `fdem check` and tests.

pub mod ambient;
mod bcs;
mod bodies;
mod contact;
mod make_mesh;
mod particles;
mod spheres;

pub use bcs::{body_bcs, BodyBcs, MechanicsKind, SetTarget, ThermalKind};
pub use bodies::{BodyMesh, BodySource, Motion, SavedJoints, SourceJoints, SourceMesh};
pub use contact::ContactModel;
pub use particles::SourceParticles;
pub use spheres::{place_spheres, SphereSet};

use crate::error::{Error, Result};
use crate::geometry::transform::{rotate_points, rotation_xyz_degrees, translate_points};
use crate::mechanics::ElasticMaterial;
use crate::mesh::{self, TetMesh};
use crate::scenario::{
    CapacityKind, LoadedScenario, MechanicsBcSpec, MeshSpec, ParticleOutputSpec, PenaltySpec,
    SolverSpec, ThermalBcSpec,
};

/// A material's constants (thermal ones are 0 in a purely mechanical run).
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Name.
    pub name: String,
    /// Conductivity k (W/m/K).
    pub conductivity: f64,
    /// Specific heat c (J/kg/K).
    pub specific_heat: f64,
    /// Density ρ (kg/m³).
    pub density: f64,
    /// Elastic constants, when the scenario gives them.
    pub elastic: Option<ElasticMaterial>,
    /// Fracture constants of joints made of it (issue 19).
    pub fracture: Option<crate::fracture::law::FractureMaterial>,
    /// Surface emissivity (0 when not given).
    pub emissivity: f64,
}

/// One body: a connected Tet4 mesh region with one material.
#[derive(Debug, Clone)]
pub struct Body {
    /// Name (its sets are `<name>.<set>` in the combined mesh).
    pub name: String,
    /// The scenario entry it comes from (differs from `name` for lattice copies).
    pub template: String,
    /// Index into [`Model::materials`].
    pub material: usize,
    /// Initial temperature.
    pub initial_temperature: f64,
    /// Prescribed rigid translation velocity (m/s).
    pub velocity: [f64; 3],
    /// Its nodes: global ids `node_range.0..node_range.1` (bodies in order).
    pub node_range: (u32, u32),
    /// Its elements.
    pub elem_range: (u32, u32),
    /// Held in place (mechanics).
    pub fixed: bool,
    /// Initial velocity of a free body (m/s).
    pub initial_velocity: [f64; 3],
    /// Stress-free temperature.
    pub reference_temperature: f64,
    /// Prescribed uniform heating (final temperature, duration).
    pub heating: Option<(f64, f64)>,
    /// Where its mesh comes from.
    pub source: BodySource,
}

impl Body {
    /// Whether the mechanics moves it kinematically (held in place or at a
    /// prescribed velocity) rather than by its forces.
    pub fn is_held(&self) -> bool {
        self.fixed || self.velocity != [0.0; 3]
    }
}

/// The explicit mechanics: its settings, and its conditions on named sets.
#[derive(Debug, Clone)]
pub struct MechanicsModel {
    /// Explicit step given by the scenario (else from the critical step).
    pub dt: Option<f64>,
    /// Fraction of the critical step.
    pub safety: f64,
    /// Substeps per thermal step, when decoupled (quasi-static coupling).
    pub substeps: Option<u64>,
    /// Gravity (m/s²).
    pub gravity: [f64; 3],
    /// Mass-proportional damping (1/s).
    pub damping: f64,
    /// Mass-proportional damping (1/s) of bodies touching nothing (None: `damping`).
    pub free_damping: Option<f64>,
    /// Conditions on named sets, in scenario order (held bodies are held
    /// whole besides).
    pub bcs: Vec<(SetTarget, MechanicsKind)>,
    /// Penalty contact.
    pub contact: Option<PenaltySpec>,
    /// Stop once settled (deposition).
    pub settle: Option<crate::scenario::SettleSpec>,
    /// Repartition as the bodies move (several ranks).
    pub rebalance: crate::scenario::RebalanceSpec,
}

/// The thermal problem: its settings, and its conditions on named sets.
#[derive(Debug, Clone, Default)]
pub struct ThermalProblem {
    /// θ of the theta method.
    pub theta: f64,
    /// Capacity matrix form.
    pub capacity: CapacityKind,
    /// Conduction operator form.
    pub conduction: crate::scenario::ConductionKind,
    /// Initial temperatures, prescribed temperatures (the last one given
    /// wins), fluxes and convection on named sets, in scenario order.
    pub bcs: Vec<(SetTarget, ThermalKind)>,
    /// Volumetric source per body (W/m³).
    pub source: Vec<f64>,
    /// Added to temperatures to make them absolute (K; seed 001's TOFFST).
    pub offset: f64,
    /// Free-surface convection and radiation (issue 20).
    pub ambient: Option<ambient::Ambient>,
}

/// What a run writes, and where.
#[derive(Debug, Clone)]
pub struct OutputPlan {
    /// Directory: the scenario's (resolved against its file), else
    /// `output/<stem>`; `--output` overrides it.
    pub directory: std::path::PathBuf,
    /// File stem (the scenario's, else its file's stem).
    pub stem: String,
    /// Write a restart checkpoint at the end of the run (and when the
    /// packing settles).
    pub checkpoint: bool,
    /// Also overwrite the checkpoint every N steps (0: only at the end).
    pub checkpoint_every: u64,
    /// Also a history row every N steps (0: only with the fields).
    pub history_every: u64,
    /// Particle statistics.
    pub particles: Option<ParticleOutputSpec>,
}

/// Everything a run needs, independent of the rank count, of the size of
/// the number of bodies (plus the meshes bodies are made from).
#[derive(Debug, Clone)]
pub struct Model {
    /// Materials.
    pub materials: Vec<Material>,
    /// Bodies, each with its global node and element ranges.
    pub bodies: Vec<Body>,
    /// The meshes bodies are made from.
    pub meshes: Vec<SourceMesh>,
    /// Checkpoint files bodies are taken from.
    pub checkpoints: Vec<std::path::PathBuf>,
    /// Thermal problem.
    pub thermal: ThermalProblem,
    /// Contact heat transfer, when the scenario has a `[contact]` table.
    pub contact: Option<ContactModel>,
    /// Whether the thermal problem is solved.
    pub thermal_active: bool,
    /// Mechanics, when the scenario has a `[mechanics]` table.
    pub mechanics: Option<MechanicsModel>,
    /// Free discrete-element sphere sets (issue 21).
    pub spheres: Vec<SphereSet>,
    /// Time step (s).
    pub dt: f64,
    /// Number of steps.
    pub steps: u64,
    /// Steps at which fields are written (ascending, includes 0 and `steps`).
    pub output_steps: Vec<u64>,
    /// Output files.
    pub output: OutputPlan,
    /// Linear solver of the thermal problem.
    pub solver: SolverSpec,
}

/// The most field steps a run may write (each repeats the mesh block in the rewritten XDMF).
pub const MAX_OUTPUT_STEPS: u64 = 100_000;

/// Every body made on one process ([`Model::whole_mesh`]).
#[derive(Debug, Clone, Default)]
pub struct WholeMesh {
    /// All bodies' elements in one mesh; `mesh.body[e]` indexes the bodies.
    pub mesh: TetMesh,
    /// Material of every element.
    pub material: Vec<u32>,
    /// Initial temperature per node.
    pub initial_t: Vec<f64>,
    /// Prescribed temperatures (node, value).
    pub dirichlet: Vec<(u32, f64)>,
    /// Inward fluxes on faces.
    pub flux: Vec<([u32; 3], f64)>,
    /// Convection on faces.
    pub convection: Vec<([u32; 3], f64, f64)>,
    /// Velocity conditions per node (mechanics).
    pub velocity: Vec<crate::mechanics::explicit::VelocityBc>,
    /// Traction loads per node (mechanics).
    pub traction: Vec<[f64; 3]>,
}

impl Model {
    /// Build the model: load or generate every body's mesh, check it, and
    /// resolve boundary conditions on named sets. Errors name the scenario
    /// file, the body and the set or element. The model may have
    /// [`mesh::element_limit`] Tet4 (one process holds them all: `fdem check`,
    /// tests); a run on several ranks builds with [`Model::from_scenario_on`].
    pub fn from_scenario(sc: &LoadedScenario) -> Result<Model> {
        Self::from_scenario_on(sc, 1)
    }

    /// [`Model::from_scenario`] for a run on `ranks` ranks, each of which
    /// keeps only its part after set-up: the model may have `ranks` times
    /// [`mesh::element_limit`] Tet4 ([`mesh::model_element_limit`]), while
    /// each body's own mesh (built whole on every rank) keeps the limit.
    pub fn from_scenario_on(sc: &LoadedScenario, ranks: usize) -> Result<Model> {
        let model_limit = mesh::model_element_limit(ranks);
        let over = format!(
            "more than fdem's limit of {model_limit}{}",
            if ranks > 1 {
                format!(" ({} per rank on {ranks} ranks)", mesh::element_limit())
            } else {
                String::new()
            }
        );
        let s = &sc.scenario;
        let path = sc.path.display().to_string();
        let model_err = |message: String| Error::Model {
            path: path.clone(),
            message,
        };
        let materials: Vec<Material> = s
            .materials
            .iter()
            .map(|m| Material {
                name: m.name.clone(),
                conductivity: m.conductivity.unwrap_or(0.0),
                specific_heat: m.specific_heat.unwrap_or(0.0),
                density: m.density,
                elastic: m
                    .young
                    .zip(m.poisson)
                    .map(|(young, poisson)| ElasticMaterial {
                        young,
                        poisson,
                        density: m.density,
                        expansion: m.expansion,
                        viscosity: m.viscosity,
                    }),
                fracture: m.fracture().ok().flatten(),
                emissivity: m.emissivity.unwrap_or(0.0),
            })
            .collect();
        let material_index = |n: &str| {
            materials
                .iter()
                .position(|mm| mm.name == n)
                .expect("validated") as u32
        };
        let mut bodies: Vec<Body> = Vec::new();
        let mut meshes: Vec<SourceMesh> = Vec::new();
        let mut checkpoints: Vec<std::path::PathBuf> = Vec::new();
        let mut files: Vec<crate::io::checkpoint::CheckpointFile> = Vec::new();
        let (mut n_nodes, mut n_elems) = (0u64, 0u64);
        let limit = |b: &str, copies: u128, per: usize, so_far: u64| -> Result<()> {
            let total = u128::from(so_far) + copies * per as u128;
            if total > model_limit {
                return Err(model_err(format!(
                    "body `{b}`: {copies} cop{} of its {per} Tet4 would make the model {total} Tet4, \
                     {}; run on more ranks or increase the element size",
                    if copies == 1 { "y" } else { "ies" },
                    over
                )));
            }
            Ok(())
        };
        let new_body = |b: &crate::scenario::BodySpec,
                        name: String,
                        source: BodySource,
                        nn: usize,
                        ne: usize,
                        n_nodes: &mut u64,
                        n_elems: &mut u64|
         -> Body {
            let body = Body {
                name,
                template: b.name.clone(),
                material: material_index(&b.material) as usize,
                initial_temperature: b.initial_temperature,
                velocity: b.velocity.unwrap_or([0.0; 3]),
                node_range: (*n_nodes as u32, (*n_nodes + nn as u64) as u32),
                elem_range: (*n_elems as u32, (*n_elems + ne as u64) as u32),
                fixed: b.fixed,
                initial_velocity: b.initial_velocity.unwrap_or([0.0; 3]),
                reference_temperature: b.reference_temperature.unwrap_or(b.initial_temperature),
                heating: b.heating.map(|h| (h.to, h.over)),
                source,
            };
            *n_nodes += nn as u64;
            *n_elems += ne as u64;
            body
        };
        // Snap-back is worst at the largest joint (f_t² h / (2 p_f) grows with h).
        let snap_back = |body: &str, fm: u32, src: &SourceMesh| -> Result<()> {
            let largest = src.largest_joint_area();
            if let Some(law) = materials[fm as usize].fracture {
                if largest > 0.0 {
                    law.law(crate::fracture::insert::joint_size(largest))
                        .map_err(|e| {
                            model_err(format!(
                                "body `{body}`: material `{}` (at its largest joint): {e}",
                                materials[fm as usize].name
                            ))
                        })?;
                }
            }
            Ok(())
        };
        for b in &s.bodies {
            let context = format!("{path}: body `{}`", b.name);
            if let MeshSpec::Checkpoint { file, template } = &b.mesh {
                let file = sc.resolve(file);
                let fi = match checkpoints.iter().position(|p| *p == file) {
                    Some(i) => i,
                    None => {
                        // Every rank reads the same head and fails alike: a
                        // model error, which rank 0 alone prints.
                        let f = crate::io::checkpoint::CheckpointFile::open(&file)
                            .map_err(|e| model_err(format!("body `{}`: {e}", b.name)))?;
                        checkpoints.push(file.clone());
                        files.push(f);
                        files.len() - 1
                    }
                };
                let h = &files[fi].head;
                let ids = h.bodies_of(template);
                if ids.is_empty() {
                    let mut t: Vec<&str> = h.body_templates.iter().map(String::as_str).collect();
                    t.sort_unstable();
                    t.dedup();
                    return Err(model_err(format!(
                        "body `{}`: {}: the checkpoint has no bodies from the entry `{template}`; it has: {}",
                        b.name,
                        file.display(),
                        t.join(", ")
                    )));
                }
                if !b.regions.is_empty() {
                    return Err(model_err(format!(
                        "body `{}`: regions cannot be given for bodies from a checkpoint",
                        b.name
                    )));
                }
                let elems: u64 = ids
                    .iter()
                    .map(|&i| u64::from(h.body_elems[i][1] - h.body_elems[i][0]))
                    .sum();
                if u128::from(n_elems + elems) > model_limit {
                    return Err(model_err(format!(
                        "body `{}`: the model would have {} Tet4, {}",
                        b.name,
                        n_elems + elems,
                        over
                    )));
                }
                let fracture = b
                    .fracture
                    .as_ref()
                    .map(|f| material_index(f.material.as_deref().unwrap_or(&b.material)));
                let offset = b.translate.unwrap_or([0.0; 3]);
                for i in ids {
                    let (bn, be) = (h.body_nodes[i], h.body_elems[i]);
                    let name = h.body_names[i].clone();
                    let (mut nn, ne) = ((bn[1] - bn[0]) as usize, (be[1] - be[0]) as usize);
                    // Jointed at load: each rank remakes the joints of the
                    // bodies it holds; here only their count, made one body
                    // at a time (O(body) memory), and the snap-back check.
                    let joints = match fracture {
                        None => None,
                        Some(fm) => {
                            let m = bodies::saved_mesh(&files[fi], i as u32, offset)
                                .map_err(model_err)?;
                            let material = vec![material_index(&b.material); m.tets.len()];
                            let all = vec![true; m.tets.len()];
                            let src = SourceMesh::jointed(m, material, &all, fm);
                            snap_back(&name, fm, &src)?;
                            let count = src.joints.as_ref().map_or(0, |j| u64::from(j.count));
                            if count == 0 && ne > 1 {
                                return Err(model_err(format!(
                                    "body `{}`: fracture: body `{name}` of {} has {ne} elements \
                                     and no face two of them share (already discontinuous: a \
                                     checkpoint of a jointed run?)",
                                    b.name,
                                    files[fi].path().display()
                                )));
                            }
                            nn = src.node_count();
                            Some(bodies::SavedJoints {
                                material: fm,
                                count,
                            })
                        }
                    };
                    let hex8 = h.body_hex8.get(i).copied().unwrap_or(false);
                    if hex8 && joints.is_some() {
                        return Err(model_err(format!(
                            "body `{}`: a Hex8 body from a checkpoint cannot be jointed at load",
                            b.name
                        )));
                    }
                    let source = BodySource::Saved {
                        file: fi as u32,
                        body: i as u32,
                        offset,
                        joints,
                        hex8,
                    };
                    bodies.push(new_body(
                        b,
                        name,
                        source,
                        nn,
                        ne,
                        &mut n_nodes,
                        &mut n_elems,
                    ));
                }
                continue;
            }
            let (mut m, hexes) =
                make_mesh::body_mesh(&b.mesh, sc).map_err(|source| Error::Mesh {
                    context: context.clone(),
                    source,
                })?;
            if let Some(r) = b.rotate {
                rotate_points(&mut m.nodes, &rotation_xyz_degrees(r));
            }
            if let Some(t) = b.translate {
                translate_points(&mut m.nodes, t);
            }
            m.validate().map_err(|source| Error::Mesh {
                context: context.clone(),
                source,
            })?;
            if m.tets.is_empty() {
                return Err(model_err(format!(
                    "body `{}`: mesh has no tetrahedra",
                    b.name
                )));
            }
            for (set, bx) in &b.element_sets {
                m.add_box_set(set, bx.min, bx.max)
                    .map_err(|e| model_err(format!("body `{}`: element_sets.{e}", b.name)))?;
            }
            // One body per scenario entry, whatever the file's volumes.
            m.body.iter_mut().for_each(|x| *x = 0);
            let material = material_index(&b.material) as usize;
            // Element materials: the body's, or a region's.
            let mut mat_of_elem = vec![material as u32; m.tets.len()];
            for (set, mat) in &b.regions {
                for &e in bodies::elements_of(&m, set, &b.name, "regions").map_err(model_err)? {
                    mat_of_elem[e as usize] = material_index(mat);
                }
            }
            let (m, material_vec, particles, hexes) =
                particles::split_off(b, m, mat_of_elem, hexes).map_err(model_err)?;
            let mut source = match &b.fracture {
                None => SourceMesh::new(m, material_vec),
                Some(f) => {
                    let in_set = match &f.set {
                        None => vec![true; m.tets.len()],
                        Some(set) => {
                            let elems = bodies::elements_of(&m, set, &b.name, "fracture.set")
                                .map_err(model_err)?;
                            let mut v = vec![false; m.tets.len()];
                            elems.iter().for_each(|&e| v[e as usize] = true);
                            v
                        }
                    };
                    let fm = material_index(f.material.as_deref().unwrap_or(&b.material));
                    let mut src = SourceMesh::jointed(m, material_vec, &in_set, fm);
                    if let Some(plane) = &f.initial_crack {
                        let n = src.break_on_plane(plane.point, plane.normal);
                        if n == 0 {
                            return Err(model_err(format!(
                                "body `{}`: fracture.initial_crack: no joint face lies in the plane through {:?} with normal {:?}",
                                b.name, plane.point, plane.normal
                            )));
                        }
                    }
                    snap_back(&b.name, fm, &src)?;
                    src
                }
            };
            source.particles = particles;
            if let Some(h) = hexes {
                make_mesh::hex8_allowed(b, &source, &h).map_err(model_err)?;
                source.hexes = Some(h.into());
            }
            let m = &source.mesh;
            // The body itself, its copies on a lattice, or a pack of
            // particles: refused before they are placed if the model would
            // exceed the element limit.
            let copies = match (&b.pack, &b.lattice) {
                (Some(p), _) => p.count as u128,
                (None, Some(l)) => l.count.iter().map(|&c| u128::from(c)).product(),
                (None, None) => 1,
            };
            limit(&b.name, copies, m.tets.len(), n_elems)?;
            let (nn, ne) = (source.node_count(), m.tets.len());
            let mi = meshes.len() as u32;
            if let Some(p) = &b.pack {
                let into = s
                    .bodies
                    .iter()
                    .find(|o| o.name == p.into)
                    .expect("validated");
                let interior =
                    crate::pack::ContainerInterior::from_spec(&into.mesh, into.translate)
                        .expect("validated");
                let placed = crate::pack::place(&b.name, m, p, &interior, &|f| sc.resolve(f))
                    .map_err(|msg| model_err(format!("body `{}`: pack: {msg}", b.name)))?;
                for (name, motion) in placed {
                    let source = BodySource::Mesh { mesh: mi, motion };
                    bodies.push(new_body(
                        b,
                        name,
                        source,
                        nn,
                        ne,
                        &mut n_nodes,
                        &mut n_elems,
                    ));
                }
            } else {
                let copies: Vec<(String, [f64; 3])> = match &b.lattice {
                    None => vec![(b.name.clone(), [0.0; 3])],
                    Some(l) => {
                        let mut v = Vec::new();
                        for k in 0..l.count[2] {
                            for j in 0..l.count[1] {
                                for i in 0..l.count[0] {
                                    let off = [
                                        i as f64 * l.spacing[0],
                                        j as f64 * l.spacing[1],
                                        k as f64 * l.spacing[2],
                                    ];
                                    v.push((format!("{}_{i}_{j}_{k}", b.name), off));
                                }
                            }
                        }
                        v
                    }
                };
                for (name, off) in copies {
                    let source = BodySource::Mesh {
                        mesh: mi,
                        motion: Motion::Translate(off),
                    };
                    bodies.push(new_body(
                        b,
                        name,
                        source,
                        nn,
                        ne,
                        &mut n_nodes,
                        &mut n_elems,
                    ));
                }
            }
            meshes.push(source);
        }
        drop(files);
        let names: Vec<String> = bodies.iter().map(|b| b.name.clone()).collect();
        // The set names of each body's source mesh (none for checkpoint bodies).
        let source_of = |k: usize| match &bodies[k].source {
            BodySource::Mesh { mesh, .. } => Some(&meshes[*mesh as usize].mesh),
            BodySource::Saved { .. } => None,
        };
        let sets_of = |k: usize| -> Vec<String> {
            source_of(k).map_or(Vec::new(), |m| {
                let mut v: Vec<String> = m
                    .node_sets
                    .keys()
                    .chain(m.face_sets.keys())
                    .cloned()
                    .collect();
                v.sort();
                v.dedup();
                v
            })
        };
        let node_set = |k: usize, set: &str| {
            source_of(k)
                .is_some_and(|m| m.node_sets.contains_key(set) || m.face_sets.contains_key(set))
        };
        let face_set =
            |k: usize, set: &str| source_of(k).is_some_and(|m| m.face_sets.contains_key(set));
        // A node set (or a face set's nodes), not empty.
        let nodes_target = |name: &str| -> std::result::Result<SetTarget, String> {
            let t = bcs::resolve(name, &names, sets_of, node_set)?;
            let m = source_of(t.body as usize).expect("has sets");
            if bcs::set_nodes(m, &t.set).is_empty() {
                return Err(format!(
                    "set `{}.{}` is empty",
                    names[t.body as usize], t.set
                ));
            }
            Ok(t)
        };
        let faces_target = |name: &str| -> std::result::Result<SetTarget, String> {
            let t = bcs::resolve(name, &names, sets_of, face_set)
                .map_err(|e| format!("{e} (flux and convection need a face set)"))?;
            let m = source_of(t.body as usize).expect("has sets");
            if m.face_sets.get(&t.set).is_none_or(Vec::is_empty) {
                return Err(format!(
                    "face set `{}.{}` is empty",
                    names[t.body as usize], t.set
                ));
            }
            Ok(t)
        };

        let thermal_spec = s.thermal_spec();
        let mut thermal = ThermalProblem {
            theta: thermal_spec.theta,
            capacity: thermal_spec.capacity,
            conduction: thermal_spec.conduction,
            source: vec![0.0; bodies.len()],
            offset: thermal_spec.temperature_offset,
            ambient: (thermal_spec.ambient.as_ref()).map(|a| ambient::Ambient::new(a, &bodies)),
            ..Default::default()
        };
        for (i, init) in thermal_spec.initial.iter().enumerate() {
            let source = |k: usize| match &bodies[k].source {
                BodySource::Mesh { mesh, .. } => Some(&meshes[*mesh as usize]),
                BodySource::Saved { .. } => None,
            };
            let t = particles::initial_target(&init.set, &names, source)
                .map_err(|m| model_err(format!("thermal.initial[{i}]: {m}")))?;
            thermal.bcs.push((t, ThermalKind::Initial(init.value)));
        }
        for (i, bc) in thermal_spec.bc.iter().enumerate() {
            let key = format!("thermal.bc[{i}]");
            let err = |m: String| model_err(format!("{key}: {m}"));
            match bc {
                ThermalBcSpec::Temperature { set, value, ramp } => {
                    let t = nodes_target(set).map_err(err)?;
                    thermal
                        .bcs
                        .push((t, ThermalKind::Temperature(*value, ramp.unwrap_or(0.0))));
                }
                ThermalBcSpec::Flux { set, value } => {
                    let t = faces_target(set).map_err(err)?;
                    thermal.bcs.push((t, ThermalKind::Flux(*value)));
                }
                ThermalBcSpec::Convection { set, h, ambient } => {
                    let t = faces_target(set).map_err(err)?;
                    thermal.bcs.push((t, ThermalKind::Convection(*h, *ambient)));
                }
                ThermalBcSpec::Source { body, value } => {
                    let b = bodies
                        .iter()
                        .position(|x| &x.name == body)
                        .expect("validated");
                    thermal.source[b] += value;
                }
            }
        }

        let steps = s.num_steps();
        let dt = s.time.dt;
        let mut output_steps = vec![0, steps];
        if let Some(every) = s.output.every.filter(|&e| e > 0) {
            // Counted before they are listed: a tiny dt or a long run must
            // not make the list itself unbounded.
            let count = (steps / every).saturating_add(1);
            if count > MAX_OUTPUT_STEPS {
                return Err(model_err(format!(
                    "output.every = {every} writes {count} field steps over the run's {steps} \
                     steps, more than the limit of {MAX_OUTPUT_STEPS}; increase output.every"
                )));
            }
            output_steps.extend((0..=steps).step_by(every as usize));
        }
        for &t in &s.output.times {
            let k = (t / dt).round() as u64;
            if k > steps {
                return Err(model_err(format!(
                    "output.times: {t} s is after the end of the run ({} s)",
                    steps as f64 * dt
                )));
            }
            output_steps.push(k);
        }
        output_steps.sort_unstable();
        output_steps.dedup();

        let contact = match &s.contact {
            None => None,
            Some(c) => Some(contact::contact_model(c, &materials).map_err(model_err)?),
        };

        let mechanics = match &s.mechanics {
            None => None,
            Some(ms) => {
                let mut bcs = Vec::new();
                for (i, spec) in ms.bc.iter().enumerate() {
                    let key = format!("mechanics.bc[{i}]");
                    let err = |m: String| model_err(format!("{key}: {m}"));
                    match spec {
                        MechanicsBcSpec::Fixed { set, components } => {
                            let t = nodes_target(set).map_err(err)?;
                            let mut comps = [components.is_none(); 3];
                            for c in components.iter().flatten() {
                                comps[match c.as_str() {
                                    "x" => 0,
                                    "y" => 1,
                                    _ => 2,
                                }] = true;
                            }
                            bcs.push((t, MechanicsKind::Fixed(comps)));
                        }
                        MechanicsBcSpec::Velocity { set, value } => {
                            let t = nodes_target(set).map_err(err)?;
                            bcs.push((t, MechanicsKind::Velocity(*value)));
                        }
                        MechanicsBcSpec::Traction { set, value } => {
                            let t = faces_target(set).map_err(err)?;
                            bcs.push((t, MechanicsKind::Traction(*value)));
                        }
                    }
                }
                // Every element's material needs elastic constants.
                for b in &bodies {
                    let mats: Vec<u32> = match &b.source {
                        BodySource::Mesh { mesh, .. } => meshes[*mesh as usize].material.clone(),
                        BodySource::Saved { .. } => vec![b.material as u32],
                    };
                    if let Some(k) = mats
                        .iter()
                        .position(|&m| materials[m as usize].elastic.is_none())
                    {
                        let m = mats[k] as usize;
                        return Err(model_err(format!(
                            "element {}: material `{}` has no elastic constants",
                            b.elem_range.0 as usize + k,
                            materials[m].name
                        )));
                    }
                }
                Some(MechanicsModel {
                    dt: ms.dt,
                    safety: ms.safety,
                    substeps: ms.substeps,
                    gravity: ms.gravity,
                    damping: ms.damping,
                    free_damping: ms.free_damping,
                    bcs,
                    contact: ms.contact.clone(),
                    settle: ms.settle,
                    rebalance: ms.rebalance,
                })
            }
        };

        Ok(Model {
            materials,
            bodies,
            meshes,
            checkpoints,
            thermal,
            contact,
            dt,
            steps,
            output_steps,
            output: OutputPlan {
                directory: s
                    .output
                    .directory
                    .as_ref()
                    .map(|d| sc.resolve(d))
                    .unwrap_or_else(|| std::path::PathBuf::from("output").join(sc.output_stem())),
                stem: sc.output_stem(),
                checkpoint: s.output.checkpoint,
                checkpoint_every: s.output.checkpoint_every,
                history_every: s.output.history_every,
                particles: s.output.particles.clone(),
            },
            solver: s.solver.clone(),
            thermal_active: s.has_thermal(),
            mechanics,
            spheres: spheres::sphere_sets(s),
        })
    }

    /// Prescribed temperature at time `t` of node `n` (global id) whose
    /// initial temperature is `t0` (runs without a thermal problem): the
    /// initial value, ramped by the body's heating.
    pub fn prescribed_temperature(&self, n: u32, t0: f64, t: f64) -> f64 {
        match self.bodies[self.body_of_node(n)].heating {
            None => t0,
            Some((to, over)) => {
                let f = if over > 0.0 { (t / over).min(1.0) } else { 1.0 };
                t0 + (to - t0) * f
            }
        }
    }

    /// Nodes and elements of the whole model (the bodies' ranges end there).
    pub fn totals(&self) -> (u64, u64) {
        self.bodies.last().map_or((0, 0), |b| {
            (u64::from(b.node_range.1), u64::from(b.elem_range.1))
        })
    }

    /// Whether any body has a prescribed heating.
    pub fn has_heating(&self) -> bool {
        self.bodies.iter().any(|b| b.heating.is_some())
    }

    /// Whether any body moves.
    pub fn has_motion(&self) -> bool {
        self.bodies.iter().any(|b| b.velocity != [0.0; 3])
    }

    /// The conditions on body `b`, made on its mesh (`mesh` of it).
    pub fn body_bcs(&self, b: usize, mesh: &BodyMesh) -> BodyBcs {
        let body = &self.bodies[b];
        let on = |t: &SetTarget| t.body as usize == b;
        let thermal: Vec<(&SetTarget, ThermalKind)> = self
            .thermal
            .bcs
            .iter()
            .filter(|(t, _)| on(t))
            .map(|(t, k)| (t, *k))
            .collect();
        let mechanics: Option<Vec<(&SetTarget, MechanicsKind)>> =
            self.mechanics.as_ref().map(|m| {
                m.bcs
                    .iter()
                    .filter(|(t, _)| on(t))
                    .map(|(t, k)| (t, *k))
                    .collect()
            });
        let held = if body.fixed {
            Some([0.0; 3])
        } else if body.velocity != [0.0; 3] {
            Some(body.velocity)
        } else {
            None
        };
        body_bcs(
            mesh.nodes.len(),
            &mesh.nodes,
            mesh.source.as_deref(),
            body.initial_temperature,
            held,
            &thermal,
            mechanics.as_deref(),
        )
    }

    /// Make every body on this process: the whole mesh (sets prefixed by
    /// the body names, as `<body>.<set>`), every element's material, and
    /// the conditions per node and face. For `fdem check` and tests: a run
    /// makes only the bodies each rank holds.
    pub fn whole_mesh(&self) -> Result<WholeMesh> {
        let files = self.open_checkpoints()?;
        let mut w = WholeMesh::default();
        for b in 0..self.bodies.len() {
            let m = self.body_mesh(b, &files).map_err(|message| Error::Model {
                path: self.bodies[b].name.clone(),
                message,
            })?;
            let all: Vec<u32> = (0..m.tets.len() as u32).collect();
            let m = match m.jointed_part(&all) {
                Some((jointed, _)) => jointed,
                None => m,
            };
            let bc = self.body_bcs(b, &m);
            let n0 = w.mesh.nodes.len() as u32;
            let name = &self.bodies[b].name;
            let mut part = TetMesh {
                nodes: m.nodes.clone(),
                tets: m.tets.to_vec(),
                body: vec![0; m.tets.len()],
                ..Default::default()
            };
            if let Some(src) = &m.source {
                part.node_sets = prefix_sets(src.node_sets.clone(), name);
                part.face_sets = prefix_sets(src.face_sets.clone(), name);
                part.elem_sets = prefix_sets(src.elem_sets.clone(), name);
            }
            w.mesh.append(part, b as u32);
            w.material.extend_from_slice(&m.material);
            w.initial_t.extend_from_slice(&bc.initial_t);
            for (i, d) in bc.dirichlet.iter().enumerate() {
                if let Some(v) = d {
                    w.dirichlet.push((n0 + i as u32, *v));
                }
            }
            w.flux
                .extend(bc.flux.iter().map(|(f, q)| (f.map(|n| n + n0), *q)));
            w.convection.extend(
                bc.convection
                    .iter()
                    .map(|(f, h, t)| (f.map(|n| n + n0), *h, *t)),
            );
            w.velocity.extend_from_slice(&bc.velocity);
            w.traction.extend_from_slice(&bc.traction);
        }
        Ok(w)
    }

    /// Body of element `e` (bodies own consecutive, ascending element ranges).
    pub fn body_of_elem(&self, e: u32) -> usize {
        self.bodies
            .partition_point(|b| b.elem_range.1 <= e)
            .min(self.bodies.len().saturating_sub(1))
    }

    /// Body of node `n` (bodies own consecutive, ascending node ranges).
    pub fn body_of_node(&self, n: u32) -> usize {
        self.bodies
            .partition_point(|b| b.node_range.1 <= n)
            .min(self.bodies.len().saturating_sub(1))
    }
}

fn prefix_sets<V>(
    sets: std::collections::BTreeMap<String, V>,
    name: &str,
) -> std::collections::BTreeMap<String, V> {
    sets.into_iter()
        .map(|(k, v)| (format!("{name}.{k}"), v))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    const TWO: &str = r#"
[time]
dt = 1.0
steps = 1
[[materials]]
name = "steel"
conductivity = 50.0
specific_heat = 500.0
density = 7800.0
[[materials]]
name = "glass"
conductivity = 1.0
specific_heat = 800.0
density = 2500.0
[[bodies]]
name = "a"
material = "steel"
mesh = { kind = "box", size = [0.1, 0.1, 0.1], element_size = 0.1 }
rotate = [0.0, 0.0, 90.0]
[[bodies]]
name = "g"
material = "glass"
mesh = { kind = "box", size = [0.1, 0.1, 0.1], element_size = 0.1 }
lattice = { count = [2, 1, 1], spacing = [0.2, 0.0, 0.0] }
[contact]
resistance = 0.01
[[contact.pair]]
materials = ["glass", "steel"]
conductance = 50.0
"#;

    fn model() -> Model {
        let sc = crate::scenario::parse_str(TWO, Path::new("t.toml"), &[]).unwrap();
        Model::from_scenario(&sc).unwrap()
    }

    #[test]
    fn the_model_limit_grows_with_the_ranks_a_body_mesh_limit_does_not() {
        // 18 Tet4: body a (6) and two copies of g (6 each).
        let sc = crate::scenario::parse_str(TWO, Path::new("t.toml"), &[]).unwrap();
        let on = |limit, ranks| {
            crate::mesh::with_element_limit(limit, || {
                Model::from_scenario_on(&sc, ranks).map(|m| m.totals().1)
            })
        };
        let one = on(17, 1).unwrap_err().to_string();
        assert!(one.contains("limit of 17;"), "{one}");
        assert_eq!(on(18, 1).unwrap(), 18);
        assert_eq!(on(9, 2).unwrap(), 18);
        let two = on(8, 2).unwrap_err().to_string();
        assert!(two.contains("limit of 16 (8 per rank on 2 ranks)"), "{two}");
        // A body's own mesh is built whole on every rank: its limit stays.
        assert!(on(5, 4).is_err());
        assert_eq!(
            crate::mesh::model_element_limit(0),
            crate::mesh::MAX_ELEMENTS as u128
        );
        assert_eq!(
            crate::mesh::model_element_limit(1 << 20),
            u128::from(crate::mesh::MAX_MODEL_ELEMENTS)
        );
    }

    #[test]
    fn pair_resistance_overrides_the_default() {
        let m = model();
        let w = m.whole_mesh().unwrap();
        let mat = |b: usize| w.material[m.bodies[b].elem_range.0 as usize];
        let (steel, glass, glass2) = (mat(0), mat(1), mat(2));
        assert_eq!(m.resistance(steel, glass), 1.0 / 50.0);
        assert_eq!(m.resistance(glass, steel), 1.0 / 50.0);
        assert_eq!(m.resistance(glass, glass2), 0.01);
    }

    #[test]
    fn rotation_and_lattice_place_the_copies() {
        let m = model();
        let w = m.whole_mesh().unwrap();
        assert_eq!(m.bodies.len(), 3);
        assert_eq!(m.bodies[1].name, "g_0_0_0");
        assert_eq!(m.bodies[2].name, "g_1_0_0");
        assert_eq!(m.bodies[2].template, "g");
        // 90° about z maps (0.1, 0, 0) to (0, 0.1, 0): body a spans x in [-0.1, 0].
        let (lo, hi) = m.bodies[0].node_range;
        let xs: Vec<f64> = (lo..hi).map(|n| w.mesh.nodes[n as usize][0]).collect();
        assert!(xs.iter().all(|&x| (-0.1 - 1e-12..=1e-12).contains(&x)));
        // The second copy is shifted by the spacing.
        let (lo2, _) = m.bodies[2].node_range;
        let (lo1, _) = m.bodies[1].node_range;
        assert!(
            (w.mesh.nodes[lo2 as usize][0] - w.mesh.nodes[lo1 as usize][0] - 0.2).abs() < 1e-15
        );
        assert!(w.mesh.face_sets.contains_key("g_1_0_0.xmax"));
    }
}
