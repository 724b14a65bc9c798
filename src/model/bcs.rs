//! Boundary conditions on named sets: the scenario's set names resolved
//! to a body and one of its source mesh's sets when the model is built
//! (errors name the key), and the conditions applied to one body's mesh
//! where the body is made (seed 000 eqs 18–20 for flux and convection;
//! velocities and tractions for the mechanics).

use crate::mechanics::explicit::VelocityBc;
use crate::mesh::TetMesh;

/// A named set of one body: the body, and the set's name in its source mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SetTarget {
    /// Body index.
    pub body: u32,
    /// Set name in the body's source mesh.
    pub set: String,
}

/// What a thermal condition prescribes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ThermalKind {
    /// Initial temperature of the set's nodes.
    Initial(f64),
    /// Prescribed temperature (Dirichlet) of the set's nodes, reached
    /// linearly from their initial temperature over the ramp (s; 0: at once).
    Temperature(f64, f64),
    /// Inward heat flux (W/m²) on the set's faces.
    Flux(f64),
    /// Convection h (W/m²/K) to T_env on the set's faces.
    Convection(f64, f64),
}

/// What a mechanical condition prescribes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MechanicsKind {
    /// Hold the listed components.
    Fixed([bool; 3]),
    /// Prescribed velocity components (NaN: free).
    Velocity([f64; 3]),
    /// Traction (Pa) on the set's faces.
    Traction([f64; 3]),
}

/// One body's boundary conditions, per node of its mesh and per face.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BodyBcs {
    /// Initial temperature per node.
    pub initial_t: Vec<f64>,
    /// Prescribed temperature per node (the last condition naming it).
    pub dirichlet: Vec<Option<f64>>,
    /// Per node: the seconds its prescribed temperature ramps over (0: none).
    pub dirichlet_ramp: Vec<f64>,
    /// Inward flux on faces (body nodes, W/m²).
    pub flux: Vec<([u32; 3], f64)>,
    /// Convection on faces (body nodes, h, T_env).
    pub convection: Vec<([u32; 3], f64, f64)>,
    /// Velocity conditions per node (mechanics; empty without).
    pub velocity: Vec<VelocityBc>,
    /// Dead-load nodal forces from tractions per node (mechanics; empty without).
    pub traction: Vec<[f64; 3]>,
}

/// Resolve a scenario's set name against the bodies' names and their
/// source meshes' sets: `<body>.<set>` exactly, or `<set>` when exactly one
/// body has a set of that name. `has(b, set)` tells whether body b's source
/// has a set named so (of the kinds the condition accepts).
pub fn resolve(
    name: &str,
    body_names: &[String],
    sets_of: impl Fn(usize) -> Vec<String>,
    has: impl Fn(usize, &str) -> bool,
) -> Result<SetTarget, String> {
    // `<body>.<set>`: try every dot (body names may hold dots).
    let mut exact = Vec::new();
    for (i, _) in name.match_indices('.') {
        let (b, s) = (&name[..i], &name[i + 1..]);
        for (k, bn) in body_names.iter().enumerate() {
            if bn == b && has(k, s) {
                exact.push(SetTarget {
                    body: k as u32,
                    set: s.to_string(),
                });
            }
        }
    }
    if exact.len() == 1 {
        return Ok(exact.remove(0));
    }
    let hits: Vec<SetTarget> = (0..body_names.len())
        .filter(|&k| has(k, name))
        .map(|k| SetTarget {
            body: k as u32,
            set: name.to_string(),
        })
        .collect();
    let full = |t: &SetTarget| format!("{}.{}", body_names[t.body as usize], t.set);
    match hits.len() {
        1 => Ok(hits.into_iter().next().expect("one")),
        0 => {
            // Every set of every body, at most 40 of them named.
            let mut all: Vec<String> = Vec::new();
            let mut more = 0usize;
            for (k, bn) in body_names.iter().enumerate() {
                for s in sets_of(k) {
                    if all.len() < 40 {
                        all.push(format!("{bn}.{s}"));
                    } else {
                        more += 1;
                    }
                }
            }
            all.sort();
            all.dedup();
            let tail = if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            };
            Err(format!(
                "no set named `{name}`; available: {}{tail}",
                all.join(", ")
            ))
        }
        n => {
            let mut names: Vec<String> = hits.iter().take(20).map(full).collect();
            names.sort();
            let tail = if n > 20 {
                format!(" and {} more", n - 20)
            } else {
                String::new()
            };
            Err(format!(
                "set name `{name}` is ambiguous: {}{tail}; qualify it as <body>.<set>",
                names.join(", ")
            ))
        }
    }
}

/// The nodes of a node set or face set of `mesh` (sorted, unique).
pub fn set_nodes(mesh: &TetMesh, set: &str) -> Vec<u32> {
    mesh.set_nodes(set).unwrap_or_default()
}

/// The nodes an initial temperature on `set` reaches: a node or face
/// set's, or the nodes of an element set's elements (sorted, unique).
pub fn initial_nodes(mesh: &TetMesh, set: &str) -> Vec<u32> {
    match (mesh.set_nodes(set), mesh.elem_sets.get(set)) {
        (Some(n), _) => n,
        (None, Some(elems)) => {
            let mut n: Vec<u32> = elems.iter().flat_map(|&e| mesh.tets[e as usize]).collect();
            n.sort_unstable();
            n.dedup();
            n
        }
        (None, None) => Vec::new(),
    }
}

/// The body-wide conditions of one body and the set conditions `thermal`
/// and `mechanics` (in scenario order, those on this body) applied to its
/// mesh `source` (None for a body without sets) of `nn` nodes; `held` the
/// body's velocity when it is held (fixed or kinematic); `nodes` the node
/// positions (tractions act on the reference areas).
#[allow(clippy::too_many_arguments)]
pub fn body_bcs(
    nn: usize,
    nodes: &[[f64; 3]],
    source: Option<&TetMesh>,
    initial_temperature: f64,
    held: Option<[f64; 3]>,
    thermal: &[(&SetTarget, ThermalKind)],
    mechanics: Option<&[(&SetTarget, MechanicsKind)]>,
) -> BodyBcs {
    let mut bc = BodyBcs {
        initial_t: vec![initial_temperature; nn],
        dirichlet: vec![None; nn],
        dirichlet_ramp: vec![0.0; nn],
        ..Default::default()
    };
    let empty = TetMesh::default();
    let mesh = source.unwrap_or(&empty);
    for (t, kind) in thermal {
        match *kind {
            ThermalKind::Initial(v) => {
                for n in initial_nodes(mesh, &t.set) {
                    bc.initial_t[n as usize] = v;
                }
            }
            ThermalKind::Temperature(v, ramp) => {
                for n in set_nodes(mesh, &t.set) {
                    bc.dirichlet[n as usize] = Some(v);
                    bc.dirichlet_ramp[n as usize] = ramp;
                }
            }
            ThermalKind::Flux(q) => {
                let faces = mesh.face_sets.get(&t.set).map_or(&[][..], Vec::as_slice);
                bc.flux.extend(faces.iter().map(|&f| (f, q)));
            }
            ThermalKind::Convection(h, te) => {
                let faces = mesh.face_sets.get(&t.set).map_or(&[][..], Vec::as_slice);
                bc.convection.extend(faces.iter().map(|&f| (f, h, te)));
            }
        }
    }
    // A prescribed temperature is the node's initial one, unless it ramps
    // there from the initial one.
    for (n, d) in bc.dirichlet.iter().enumerate() {
        match d {
            Some(v) if bc.dirichlet_ramp[n] == 0.0 => bc.initial_t[n] = *v,
            _ => {}
        }
    }
    if let Some(mech) = mechanics {
        bc.velocity = vec![held.map_or([None; 3], |v| v.map(Some)); nn];
        bc.traction = vec![[0.0; 3]; nn];
        for (t, kind) in mech {
            match *kind {
                MechanicsKind::Fixed(comps) => {
                    for n in set_nodes(mesh, &t.set) {
                        for (v, &c) in bc.velocity[n as usize].iter_mut().zip(&comps) {
                            if c {
                                *v = Some(0.0);
                            }
                        }
                    }
                }
                MechanicsKind::Velocity(value) => {
                    for n in set_nodes(mesh, &t.set) {
                        for (v, &x) in bc.velocity[n as usize].iter_mut().zip(&value) {
                            if !x.is_nan() {
                                *v = Some(x);
                            }
                        }
                    }
                }
                MechanicsKind::Traction(value) => {
                    let faces = mesh.face_sets.get(&t.set).map_or(&[][..], Vec::as_slice);
                    for f in faces {
                        let p = f.map(|n| nodes[n as usize]);
                        let area = crate::geometry::polygon_area(&p);
                        for &n in f {
                            for (t, &x) in bc.traction[n as usize].iter_mut().zip(&value) {
                                // Not numbered in the seeds: a constant traction t on a linear triangle gives t A/3 per node.
                                *t += x * area / 3.0;
                            }
                        }
                    }
                }
            }
        }
    }
    bc
}
