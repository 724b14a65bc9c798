//! The data model every stage shares: the combined Tet4 mesh of all
//! bodies, materials, bodies, and the thermal problem resolved to nodes and
//! faces. Built from a scenario; holds no MPI or PETSc state.
//!
//! Later stages extend it (contact pairs and conductance, mechanical
//! materials and constraints, joints) without changing what is here.

use crate::contact::DeltaT;
use crate::error::{Error, Result};
use crate::geometry::transform::{rotate_points, rotation_xyz_degrees, translate_points};
use crate::mechanics::explicit::VelocityBc;
use crate::mechanics::ElasticMaterial;
use crate::mesh::{self, TetMesh};
use crate::scenario::{
    contact_resistance, CapacityKind, LoadedScenario, MechanicsBcSpec, MeshSpec,
    ParticleOutputSpec, PenaltySpec, SolverSpec, ThermalBcSpec,
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
    /// Its nodes: `node_range.0..node_range.1` in the combined mesh.
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
}

impl Body {
    /// Whether the mechanics moves it kinematically (held in place or at a
    /// prescribed velocity) rather than by its forces.
    pub fn is_held(&self) -> bool {
        self.fixed || self.velocity != [0.0; 3]
    }
}

/// The explicit mechanics resolved to nodes and faces (original numbering).
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
    /// Velocity conditions per node (fixed and kinematic bodies included).
    pub bc: Vec<VelocityBc>,
    /// Dead-load nodal forces from tractions (N), per node.
    pub traction: Vec<[f64; 3]>,
    /// Penalty contact.
    pub contact: Option<PenaltySpec>,
    /// Stop once settled (deposition).
    pub settle: Option<crate::scenario::SettleSpec>,
}

/// The thermal problem resolved to nodes and faces (original numbering).
#[derive(Debug, Clone, Default)]
pub struct ThermalProblem {
    /// θ of the theta method.
    pub theta: f64,
    /// Capacity matrix form.
    pub capacity: CapacityKind,
    /// Conduction operator form.
    pub conduction: crate::scenario::ConductionKind,
    /// Prescribed temperatures (node, value); last one given wins.
    pub dirichlet: Vec<(u32, f64)>,
    /// Prescribed inward flux on faces (face nodes, W/m²).
    pub flux: Vec<([u32; 3], f64)>,
    /// Convection on faces (face nodes, h, T_env).
    pub convection: Vec<([u32; 3], f64, f64)>,
    /// Volumetric source per body (W/m³).
    pub source: Vec<f64>,
    /// Initial nodal temperatures.
    pub initial: Vec<f64>,
}

/// Contact heat transfer settings resolved to material indices.
#[derive(Debug, Clone)]
pub struct ContactModel {
    /// Rc between materials i and j (symmetric; infinite: no heat).
    pub resistance: Vec<Vec<f64>>,
    /// How ΔT is taken.
    pub delta_t: DeltaT,
    /// The local-ΔT block form.
    pub operator: crate::contact::ContactOperator,
    /// Detection cadence in steps (0: once).
    pub every: u64,
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
    /// Particle statistics.
    pub particles: Option<ParticleOutputSpec>,
}

/// Everything a run needs, independent of the rank count.
#[derive(Debug, Clone)]
pub struct Model {
    /// All bodies' elements in one mesh; `mesh.body[e]` indexes `bodies`.
    pub mesh: TetMesh,
    /// Materials.
    pub materials: Vec<Material>,
    /// Bodies.
    pub bodies: Vec<Body>,
    /// Thermal problem.
    pub thermal: ThermalProblem,
    /// Contact heat transfer, when the scenario has a `[contact]` table.
    pub contact: Option<ContactModel>,
    /// Whether the thermal problem is solved.
    pub thermal_active: bool,
    /// Mechanics, when the scenario has a `[mechanics]` table.
    pub mechanics: Option<MechanicsModel>,
    /// Material of every element (index into `materials`).
    pub elem_material: Vec<u32>,
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

/// The most output steps (field steps in the HDF5/XDMF series) a run may
/// write: every step repeats the mesh block in the XDMF index, which is
/// rewritten after each step.
pub const MAX_OUTPUT_STEPS: u64 = 100_000;

impl Model {
    /// Build the model: load or generate every body's mesh, check it, and
    /// resolve boundary conditions on named sets. Errors name the scenario
    /// file, the body and the set or element.
    pub fn from_scenario(sc: &LoadedScenario) -> Result<Model> {
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
            })
            .collect();
        let material_index = |n: &str| {
            materials
                .iter()
                .position(|mm| mm.name == n)
                .expect("validated") as u32
        };
        let mut combined = TetMesh::default();
        let mut bodies = Vec::new();
        let mut elem_material: Vec<u32> = Vec::new();
        let mut checkpoints: std::collections::BTreeMap<
            std::path::PathBuf,
            crate::io::checkpoint::Checkpoint,
        > = Default::default();
        for b in &s.bodies {
            let context = format!("{path}: body `{}`", b.name);
            if let MeshSpec::Checkpoint { file, template } = &b.mesh {
                let file = sc.resolve(file);
                if !checkpoints.contains_key(&file) {
                    // Every rank reads the same file and fails alike: a model
                    // error, which rank 0 alone prints.
                    let ck = crate::io::checkpoint::Checkpoint::read(&file)
                        .map_err(|e| model_err(format!("body `{}`: {e}", b.name)))?;
                    checkpoints.insert(file.clone(), ck);
                }
                let copies =
                    crate::pack::from_checkpoint(&checkpoints[&file], template).map_err(|m| {
                        model_err(format!("body `{}`: {}: {m}", b.name, file.display()))
                    })?;
                if !b.regions.is_empty() {
                    return Err(model_err(format!(
                        "body `{}`: regions cannot be given for bodies from a checkpoint",
                        b.name
                    )));
                }
                let material = material_index(&b.material) as usize;
                let total =
                    combined.tets.len() + copies.iter().map(|c| c.1.tets.len()).sum::<usize>();
                if total > mesh::MAX_ELEMENTS {
                    return Err(model_err(format!(
                        "body `{}`: the model would have {total} Tet4, more than fdem's limit of {}",
                        b.name,
                        mesh::MAX_ELEMENTS
                    )));
                }
                for (name, mut c) in copies {
                    if let Some(t) = b.translate {
                        translate_points(&mut c.nodes, t);
                    }
                    c.validate().map_err(|source| Error::Mesh {
                        context: format!("{context} ({name} from {})", file.display()),
                        source,
                    })?;
                    let ne = c.tets.len();
                    push_body(&mut combined, &mut bodies, b, name, c, material);
                    elem_material.extend(std::iter::repeat_n(material as u32, ne));
                }
                continue;
            }
            let mut m = match &b.mesh {
                MeshSpec::Box {
                    origin,
                    size,
                    element_size,
                } => mesh::generate::box_mesh(*origin, *size, *element_size),
                MeshSpec::Cylinder {
                    center,
                    radius,
                    width,
                    element_size,
                    boundary,
                } => mesh::generate::cylinder_mesh(
                    *center,
                    *radius,
                    *width,
                    *element_size,
                    *boundary,
                ),
                MeshSpec::Annulus {
                    center,
                    inner_radius,
                    radius,
                    width,
                    element_size,
                } => mesh::generate::annulus_mesh(
                    *center,
                    *inner_radius,
                    *radius,
                    *width,
                    *element_size,
                ),
                MeshSpec::Concentric {
                    center,
                    core_radius,
                    radius,
                    width,
                    element_size,
                } => mesh::generate::concentric_cylinder_mesh(
                    *center,
                    *core_radius,
                    *radius,
                    *width,
                    *element_size,
                ),
                MeshSpec::Nut {
                    center,
                    across_flats,
                    hole_radius,
                    thickness,
                    per_side,
                    radial,
                    layers,
                } => mesh::nut::nut_mesh(
                    *center,
                    *across_flats,
                    *hole_radius,
                    *thickness,
                    *per_side,
                    *radial,
                    *layers,
                ),
                MeshSpec::Container {
                    center,
                    inner_radius,
                    wall,
                    bottom,
                    height,
                    element_size,
                } => mesh::container::container_mesh(
                    *center,
                    *inner_radius,
                    *wall,
                    bottom.unwrap_or(*wall),
                    *height,
                    *element_size,
                ),
                MeshSpec::Checkpoint { .. } => unreachable!("handled above"),
                MeshSpec::Gmsh { file } => mesh::gmsh::read_msh(&sc.resolve(file)),
            }
            .map_err(|source| Error::Mesh {
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
            // One body per scenario entry, whatever the file's volumes.
            m.body.iter_mut().for_each(|x| *x = 0);
            let material = material_index(&b.material) as usize;
            // Element materials: the body's, or a region's.
            let mut mat_of_elem = vec![material as u32; m.tets.len()];
            for (set, mat) in &b.regions {
                let elems = m.elem_sets.get(set).ok_or_else(|| {
                    let names: Vec<&str> = m.elem_sets.keys().map(String::as_str).collect();
                    model_err(format!(
                        "body `{}`: regions: no element set `{set}` in its mesh; available: {}",
                        b.name,
                        names.join(", ")
                    ))
                })?;
                for &e in elems {
                    mat_of_elem[e as usize] = material_index(mat);
                }
            }
            // The body itself, its copies on a lattice, or a pack of
            // particles: refused before they are built if the model would
            // exceed the element limit.
            let copies = match (&b.pack, &b.lattice) {
                (Some(p), _) => p.count as u128,
                (None, Some(l)) => l.count.iter().map(|&c| u128::from(c)).product(),
                (None, None) => 1,
            };
            let total = combined.tets.len() as u128 + copies * m.tets.len() as u128;
            if total > mesh::MAX_ELEMENTS as u128 {
                return Err(model_err(format!(
                    "body `{}`: {copies} cop{} of its {} Tet4 would make the model {total} Tet4, \
                     more than fdem's limit of {} (the mesh is kept on every rank)",
                    b.name,
                    if copies == 1 { "y" } else { "ies" },
                    m.tets.len(),
                    mesh::MAX_ELEMENTS
                )));
            }
            if let Some(p) = &b.pack {
                let into = s
                    .bodies
                    .iter()
                    .find(|o| o.name == p.into)
                    .expect("validated");
                let interior =
                    crate::pack::ContainerInterior::from_spec(&into.mesh, into.translate)
                        .expect("validated");
                let copies = crate::pack::place(&b.name, &m, p, &interior, &|f| sc.resolve(f))
                    .map_err(|msg| model_err(format!("body `{}`: pack: {msg}", b.name)))?;
                for (name, c) in copies {
                    push_body(&mut combined, &mut bodies, b, name, c, material);
                    elem_material.extend_from_slice(&mat_of_elem);
                }
                continue;
            }
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
                let mut c = m.clone();
                translate_points(&mut c.nodes, off);
                push_body(&mut combined, &mut bodies, b, name, c, material);
                elem_material.extend_from_slice(&mat_of_elem);
            }
        }

        let thermal_spec = s.thermal_spec();
        let mut thermal = ThermalProblem {
            theta: thermal_spec.theta,
            capacity: thermal_spec.capacity,
            conduction: thermal_spec.conduction,
            source: vec![0.0; bodies.len()],
            initial: vec![0.0; combined.nodes.len()],
            ..Default::default()
        };
        for b in &bodies {
            for n in b.node_range.0..b.node_range.1 {
                thermal.initial[n as usize] = b.initial_temperature;
            }
        }
        for (i, init) in thermal_spec.initial.iter().enumerate() {
            let nodes = resolve_nodes(&combined, &init.set)
                .map_err(|m| model_err(format!("thermal.initial[{i}]: {m}")))?;
            for n in nodes {
                thermal.initial[n as usize] = init.value;
            }
        }
        for (i, bc) in thermal_spec.bc.iter().enumerate() {
            let key = format!("thermal.bc[{i}]");
            match bc {
                ThermalBcSpec::Temperature { set, value } => {
                    let nodes = resolve_nodes(&combined, set)
                        .map_err(|m| model_err(format!("{key}: {m}")))?;
                    thermal
                        .dirichlet
                        .extend(nodes.into_iter().map(|n| (n, *value)));
                }
                ThermalBcSpec::Flux { set, value } => {
                    let faces = resolve_faces(&combined, set)
                        .map_err(|m| model_err(format!("{key}: {m}")))?;
                    thermal.flux.extend(faces.into_iter().map(|f| (f, *value)));
                }
                ThermalBcSpec::Convection { set, h, ambient } => {
                    let faces = resolve_faces(&combined, set)
                        .map_err(|m| model_err(format!("{key}: {m}")))?;
                    thermal
                        .convection
                        .extend(faces.into_iter().map(|f| (f, *h, *ambient)));
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
        // Last assignment wins for nodes named by several temperature BCs.
        let mut last = std::collections::BTreeMap::new();
        for (n, v) in thermal.dirichlet.drain(..) {
            last.insert(n, v);
        }
        thermal.dirichlet = last.into_iter().collect();
        for &(n, v) in &thermal.dirichlet {
            thermal.initial[n as usize] = v;
        }

        let steps = s.num_steps();
        let dt = s.time.dt;
        let mut output_steps = vec![0, steps];
        if let Some(every) = s.output.every.filter(|&e| e > 0) {
            // Counted before they are listed: a tiny dt or a long run must
            // not make the list itself unbounded.
            let count = steps / every + 1;
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
            Some(c) => {
                let default = contact_resistance(c.resistance, c.conductance)
                    .map_err(|m| model_err(format!("contact: {m}")))?
                    .unwrap_or(f64::INFINITY);
                let nm = materials.len();
                let mut rc = vec![vec![default; nm]; nm];
                for p in &c.pair {
                    let r = contact_resistance(p.resistance, p.conductance)
                        .map_err(|m| model_err(format!("contact.pair: {m}")))?
                        .unwrap_or(f64::INFINITY);
                    let idx = |n: &str| {
                        materials
                            .iter()
                            .position(|m| m.name == n)
                            .expect("validated")
                    };
                    let (a, b) = (idx(&p.materials[0]), idx(&p.materials[1]));
                    rc[a][b] = r;
                    rc[b][a] = r;
                }
                Some(ContactModel {
                    resistance: rc,
                    delta_t: c.delta_t,
                    operator: c.operator,
                    every: c.every,
                })
            }
        };

        let mechanics = match &s.mechanics {
            None => None,
            Some(ms) => {
                let nn = combined.nodes.len();
                let mut bc: Vec<VelocityBc> = vec![[None; 3]; nn];
                for b in &bodies {
                    let held = if b.fixed {
                        Some([0.0; 3])
                    } else if b.velocity != [0.0; 3] {
                        Some(b.velocity)
                    } else {
                        None
                    };
                    if let Some(v) = held {
                        for n in b.node_range.0..b.node_range.1 {
                            bc[n as usize] = v.map(Some);
                        }
                    }
                }
                let mut traction = vec![[0.0; 3]; nn];
                for (i, spec) in ms.bc.iter().enumerate() {
                    let key = format!("mechanics.bc[{i}]");
                    match spec {
                        MechanicsBcSpec::Fixed { set, components } => {
                            let nodes = resolve_nodes(&combined, set)
                                .map_err(|m| model_err(format!("{key}: {m}")))?;
                            let comps: Vec<usize> = match components {
                                None => vec![0, 1, 2],
                                Some(c) => c
                                    .iter()
                                    .map(|x| match x.as_str() {
                                        "x" => 0,
                                        "y" => 1,
                                        _ => 2,
                                    })
                                    .collect(),
                            };
                            for n in nodes {
                                for &d in &comps {
                                    bc[n as usize][d] = Some(0.0);
                                }
                            }
                        }
                        MechanicsBcSpec::Velocity { set, value } => {
                            let nodes = resolve_nodes(&combined, set)
                                .map_err(|m| model_err(format!("{key}: {m}")))?;
                            for n in nodes {
                                for d in 0..3 {
                                    if !value[d].is_nan() {
                                        bc[n as usize][d] = Some(value[d]);
                                    }
                                }
                            }
                        }
                        MechanicsBcSpec::Traction { set, value } => {
                            let faces = resolve_faces(&combined, set)
                                .map_err(|m| model_err(format!("{key}: {m}")))?;
                            for f in faces {
                                let p = f.map(|n| combined.nodes[n as usize]);
                                let area = crate::geometry::polygon_area(&p);
                                for &n in &f {
                                    for d in 0..3 {
                                        // Not numbered in the seeds: a constant traction t on a linear triangle gives t A/3 per node.
                                        traction[n as usize][d] += value[d] * area / 3.0;
                                    }
                                }
                            }
                        }
                    }
                }
                for (e, &m) in elem_material.iter().enumerate() {
                    if materials[m as usize].elastic.is_none() {
                        return Err(model_err(format!(
                            "element {e}: material `{}` has no elastic constants",
                            materials[m as usize].name
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
                    bc,
                    traction,
                    contact: ms.contact.clone(),
                    settle: ms.settle,
                })
            }
        };

        Ok(Model {
            mesh: combined,
            materials,
            bodies,
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
                particles: s.output.particles.clone(),
            },
            solver: s.solver.clone(),
            thermal_active: s.has_thermal(),
            mechanics,
            elem_material,
        })
    }

    /// Material of element `e`.
    pub fn material_of(&self, e: usize) -> &Material {
        &self.materials[self.elem_material[e] as usize]
    }

    /// Contact resistance between materials `a` and `b` (infinite without
    /// contact heat transfer).
    pub fn resistance(&self, a: u32, b: u32) -> f64 {
        self.contact
            .as_ref()
            .map_or(f64::INFINITY, |c| c.resistance[a as usize][b as usize])
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

    /// Node positions at time `t` (bodies translated by their velocities).
    pub fn positions_at(&self, t: f64, out: &mut [[f64; 3]]) {
        for b in &self.bodies {
            for n in b.node_range.0..b.node_range.1 {
                let p = self.mesh.nodes[n as usize];
                out[n as usize] = [
                    p[0] + b.velocity[0] * t,
                    p[1] + b.velocity[1] * t,
                    p[2] + b.velocity[2] * t,
                ];
            }
        }
    }

    /// Heat capacity ρcV/4 carried by each node (the row sums of M).
    pub fn node_capacity(&self) -> Vec<f64> {
        let mut w = vec![0.0; self.mesh.nodes.len()];
        for e in 0..self.mesh.tets.len() {
            let m = self.material_of(e);
            let c = m.density * m.specific_heat * self.mesh.element_volume(e) / 4.0;
            for &n in &self.mesh.tets[e] {
                w[n as usize] += c;
            }
        }
        w
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

/// Append one body (its sets prefixed by its name) to the combined mesh.
fn push_body(
    combined: &mut TetMesh,
    bodies: &mut Vec<Body>,
    b: &crate::scenario::BodySpec,
    name: String,
    mut c: TetMesh,
    material: usize,
) {
    c.node_sets = prefix_sets(std::mem::take(&mut c.node_sets), &name);
    c.face_sets = prefix_sets(std::mem::take(&mut c.face_sets), &name);
    c.elem_sets = prefix_sets(std::mem::take(&mut c.elem_sets), &name);
    let n0 = combined.nodes.len() as u32;
    let e0 = combined.tets.len() as u32;
    combined.append(c, bodies.len() as u32);
    bodies.push(Body {
        name,
        template: b.name.clone(),
        material,
        initial_temperature: b.initial_temperature,
        velocity: b.velocity.unwrap_or([0.0; 3]),
        node_range: (n0, combined.nodes.len() as u32),
        elem_range: (e0, combined.tets.len() as u32),
        fixed: b.fixed,
        initial_velocity: b.initial_velocity.unwrap_or([0.0; 3]),
        reference_temperature: b.reference_temperature.unwrap_or(b.initial_temperature),
        heating: b.heating.map(|h| (h.to, h.over)),
    });
}

/// Find the set a scenario names: `<body>.<set>` exactly, or `<set>` when
/// exactly one body has a set of that name.
fn resolve_name<'a, V>(
    sets: &'a std::collections::BTreeMap<String, V>,
    other: &'a std::collections::BTreeMap<String, Vec<[u32; 3]>>,
    name: &str,
) -> std::result::Result<String, String> {
    if sets.contains_key(name) || other.contains_key(name) {
        return Ok(name.to_string());
    }
    let suffix = format!(".{name}");
    let mut hits: Vec<&String> = sets
        .keys()
        .chain(other.keys())
        .filter(|k| k.ends_with(&suffix))
        .collect();
    hits.sort();
    hits.dedup();
    match hits.len() {
        1 => Ok(hits[0].clone()),
        0 => {
            let mut all: Vec<&String> = sets.keys().chain(other.keys()).collect();
            all.sort();
            all.dedup();
            Err(format!(
                "no set named `{name}`; available: {}",
                all.iter()
                    .map(|s| s.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        }
        _ => Err(format!(
            "set name `{name}` is ambiguous: {}; qualify it as <body>.<set>",
            hits.iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

/// Nodes of a named node set or face set.
pub fn resolve_nodes(mesh: &TetMesh, name: &str) -> std::result::Result<Vec<u32>, String> {
    let full = resolve_name(&mesh.node_sets, &mesh.face_sets, name)?;
    let nodes = mesh
        .set_nodes(&full)
        .ok_or_else(|| format!("set `{full}` has no nodes"))?;
    if nodes.is_empty() {
        return Err(format!("set `{full}` is empty"));
    }
    Ok(nodes)
}

/// Faces of a named face set.
pub fn resolve_faces(mesh: &TetMesh, name: &str) -> std::result::Result<Vec<[u32; 3]>, String> {
    let empty = std::collections::BTreeMap::<String, Vec<[u32; 3]>>::new();
    let full = resolve_name(&mesh.face_sets, &empty, name)
        .map_err(|e| format!("{e} (flux and convection need a face set)"))?;
    let faces = mesh.face_sets.get(&full).cloned().unwrap_or_default();
    if faces.is_empty() {
        return Err(format!("face set `{full}` is empty"));
    }
    Ok(faces)
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
    fn pair_resistance_overrides_the_default() {
        let m = model();
        let mat = |b: usize| m.elem_material[m.bodies[b].elem_range.0 as usize];
        let (steel, glass, glass2) = (mat(0), mat(1), mat(2));
        assert_eq!(m.resistance(steel, glass), 1.0 / 50.0);
        assert_eq!(m.resistance(glass, steel), 1.0 / 50.0);
        assert_eq!(m.resistance(glass, glass2), 0.01);
    }

    #[test]
    fn rotation_and_lattice_place_the_copies() {
        let m = model();
        assert_eq!(m.bodies.len(), 3);
        assert_eq!(m.bodies[1].name, "g_0_0_0");
        assert_eq!(m.bodies[2].name, "g_1_0_0");
        assert_eq!(m.bodies[2].template, "g");
        // 90° about z maps (0.1, 0, 0) to (0, 0.1, 0): body a spans x in [-0.1, 0].
        let (lo, hi) = m.bodies[0].node_range;
        let xs: Vec<f64> = (lo..hi).map(|n| m.mesh.nodes[n as usize][0]).collect();
        assert!(xs.iter().all(|&x| (-0.1 - 1e-12..=1e-12).contains(&x)));
        // The second copy is shifted by the spacing.
        let (lo2, _) = m.bodies[2].node_range;
        let (lo1, _) = m.bodies[1].node_range;
        assert!(
            (m.mesh.nodes[lo2 as usize][0] - m.mesh.nodes[lo1 as usize][0] - 0.2).abs() < 1e-15
        );
        assert!(m.mesh.face_sets.contains_key("g_1_0_0.xmax"));
    }
}
