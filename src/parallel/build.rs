//! Building each rank's [`Part`] from the model without any rank making
//! every body: the bodies (and the elements of large bodies of their own
//! mesh, which are split) are cut into parts by recursive coordinate
//! bisection ([`super::rcb`]) over their centres, each rank makes only the
//! bodies and elements that fall to it, and the nodes shared by the
//! pieces of a split body find their owner (the lowest rank holding them)
//! and PETSc number through a rendezvous on their global ids.
//!
//! Collective over the communicator.

use std::collections::HashMap;

use mpi::topology::SimpleCommunicator;
use mpi::traits::*;

use super::exchange::{all_gather, all_to_all, block};
use super::{agree, LocalBcs, Part};
use crate::error::{Error, Result};
use crate::mechanics::frequency::BODY_EIGEN_MAX_NODES;
use crate::mesh::TetMesh;
use crate::model::{BodySource, Model};

/// The largest max/mean work per rank the bisection aims at.
pub const IMBALANCE: f64 = 1.05;

/// Where the bodies are when the model is cut into parts.
#[derive(Clone, Copy)]
pub enum Placement<'a> {
    /// At their model centres (the start), weighted by their elements.
    Model,
    /// The whole bodies of this rank's block of body ids at the given
    /// current centres and work (body id → centre, work), the others at
    /// their model centres: the repartition of a running deposition, whose
    /// bodies have moved and whose contacts add work. Split bodies'
    /// elements keep their model positions.
    Moved(&'a HashMap<u32, ([f64; 3], f64)>),
    /// On the parts a checkpoint saved, when it was written on as many
    /// ranks (a restart continues on the parts it stopped on); else as
    /// `Model`.
    Saved(&'a crate::io::checkpoint::CheckpointFile),
}

/// The estimated work of one element of body `b` per step, in the units
/// of the partition weights: 8 for a body whose elements compute forces
/// each substep (a free body of a mechanics run), 1 otherwise. A contact
/// pair's work is counted in the same units (a pair whose boxes are apart
/// 1, one likely to overlap 32: `dynamics::candidates`).
pub fn element_work(model: &Model, b: usize) -> f64 {
    if model.mechanics.is_some() && !model.bodies[b].is_held() {
        8.0
    } else {
        1.0
    }
}

/// What one rank holds of a body: all of it, or some of its elements.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Held {
    Whole,
    Elements(Vec<u32>),
}

impl Part {
    /// Collective. This rank's part of `model`: whole bodies, and the
    /// elements of split bodies, by recursive coordinate bisection of the
    /// bodies' (and split bodies' elements') centres weighted by their
    /// work; each rank makes only what it holds.
    pub fn build(comm: &SimpleCommunicator, model: &Model) -> Result<Part> {
        Self::build_placed(comm, model, Placement::Model)
    }

    /// Collective. As [`Part::build`], the bodies placed as `placement` says.
    pub fn build_placed(
        comm: &SimpleCommunicator,
        model: &Model,
        placement: Placement,
    ) -> Result<Part> {
        let placed = match placement {
            Placement::Moved(p) => Some(p),
            _ => None,
        };
        let size = comm.size() as usize;
        let rank = comm.rank() as usize;
        let files = model.open_checkpoints()?;
        let nb = model.bodies.len();
        let split = split_bodies(model, size);
        let split_spheres = split
            .iter()
            .zip(&model.bodies)
            .any(|(&s, body)| s && model.body_particles(body).is_some());
        let weight = |b: usize| {
            let body = &model.bodies[b];
            element_work(model, b) * f64::from(body.elem_range.1 - body.elem_range.0)
        };
        // Objects: the whole bodies of this rank's block of bodies, and the
        // elements of its block of each split body's elements.
        let (b0, b1) = block(nb as u64, size, rank);
        let mut objects: Vec<super::rcb::Object> = Vec::new();
        let mut ids: Vec<[u32; 2]> = Vec::new();
        let mut local_error = None;
        for (b, _) in split
            .iter()
            .enumerate()
            .take(b1 as usize)
            .skip(b0 as usize)
            .filter(|(_, &s)| !s)
        {
            let here = placed.and_then(|p| p.get(&(b as u32)));
            let centre = match here {
                Some(&(c, _)) => Ok(c),
                None => model.body_center(b, &files),
            };
            match centre {
                Ok(point) => {
                    objects.push(super::rcb::Object {
                        weight: here.map_or_else(|| weight(b), |&(_, w)| w),
                        point,
                    });
                    ids.push([b as u32, u32::MAX]);
                }
                Err(message) => {
                    local_error.get_or_insert(Error::Model {
                        path: model.bodies[b].name.clone(),
                        message,
                    });
                }
            }
        }
        agree(comm, local_error.map_or(Ok(()), Err))?;
        for (b, _) in split.iter().enumerate().filter(|(_, &s)| s) {
            let BodySource::Mesh { mesh, motion } = &model.bodies[b].source else {
                unreachable!("only bodies of their own mesh are split")
            };
            let src = &model.meshes[*mesh as usize];
            let ne = src.mesh.tets.len() as u64;
            let w = weight(b) / ne as f64;
            // A Hex8 body's hexes go whole: six tets, by the first (issue 21).
            let unit = if src.hexes.is_some() { 6 } else { 1 };
            let (u0, u1) = block(ne / unit, size, rank);
            for u in u0 as usize..u1 as usize {
                let e = unit as usize * u;
                let x: Vec<[f64; 3]> = (e..e + unit as usize)
                    .flat_map(|t| src.mesh.element_coords(t))
                    .collect();
                let n = x.len() as f64;
                let c = std::array::from_fn(|d| x.iter().map(|p| p[d]).sum::<f64>() / n);
                objects.push(super::rcb::Object {
                    weight: w * unit as f64,
                    point: motion.apply(c),
                });
                ids.push([b as u32, e as u32]);
            }
            // Its spheres, numbered after its elements, cut with them (issue 21).
            if let Some(p) = &src.particles {
                let (s0, s1) = block(p.region.centres.len() as u64, size, rank);
                for s in s0 as usize..s1 as usize {
                    objects.push(super::rcb::Object {
                        weight: w,
                        point: motion.apply(p.region.centres[s]),
                    });
                    ids.push([b as u32, (ne as usize + s) as u32]);
                }
            }
        }
        if let Some(m) = &model.mechanics {
            super::rcb::level(&mut objects, m.gravity);
        }
        let dest = match placement {
            Placement::Saved(f) if f.head.partition_ranks == Some(size as u64) => {
                let is_sphere = |&[b, e]: &[u32; 2]| {
                    let r = model.bodies[b as usize].elem_range;
                    e != u32::MAX && e >= r.1 - r.0
                };
                let elems: Vec<u32> = ids
                    .iter()
                    .map(|id| {
                        // A whole body (or a sphere): its first element's rank.
                        let e = if id[1] == u32::MAX || is_sphere(id) {
                            0
                        } else {
                            id[1]
                        };
                        model.bodies[id[0] as usize].elem_range.0 + e
                    })
                    .collect();
                let ranks = f.elem_ranks(&elems).map_err(|e| Error::Model {
                    path: f.path().display().to_string(),
                    message: e.to_string(),
                });
                let mut ranks = agree(comm, ranks)?;
                // A split body's spheres: the cut of the start, as its elements had
                // it (repartitions since may have moved that cut; any cut is correct).
                if split_spheres {
                    let cut = super::rcb::rcb(comm, &objects, IMBALANCE).map_err(Error::Partition);
                    let cut = agree(comm, cut)?;
                    for (k, _) in ids.iter().enumerate().filter(|(_, id)| is_sphere(id)) {
                        ranks[k] = cut[k];
                    }
                }
                ranks
            }
            _ => agree(
                comm,
                super::rcb::rcb(comm, &objects, IMBALANCE).map_err(Error::Partition),
            )?,
        };
        // Tell every object's rank.
        let mut send: Vec<Vec<u32>> = vec![Vec::new(); size];
        for (id, &r) in ids.iter().zip(&dest) {
            send[r as usize].extend_from_slice(id);
        }
        let mut held: std::collections::BTreeMap<u32, Held> = Default::default();
        for rec in all_to_all(comm, send)
            .iter()
            .flat_map(|v| v.chunks_exact(2))
        {
            let (b, e) = (rec[0], rec[1]);
            if e == u32::MAX {
                held.insert(b, Held::Whole);
            } else if let Held::Elements(v) = held.entry(b).or_insert(Held::Elements(Vec::new())) {
                let r = model.bodies[b as usize].elem_range;
                if model.body_is_hex8(b as usize) && e < r.1 - r.0 {
                    v.extend(e..e + 6);
                } else {
                    v.push(e);
                }
            }
        }
        for h in held.values_mut() {
            if let Held::Elements(v) = h {
                v.sort_unstable();
            }
        }
        let whole: Vec<u32> = held
            .iter()
            .filter(|(_, h)| matches!(h, Held::Whole))
            .map(|(&b, _)| b)
            .collect();
        let local = make_bodies(model, &files, &held);
        let local = agree(comm, local)?;
        // The particles owned here are thermal rows too (issue 21).
        let particle_rows = if model.thermal_active {
            local.spheres.iter().map(|s| s.owned.len()).sum()
        } else {
            0
        };
        // Whether a jointed body is split in a thermal run: its tied rows
        // are then numbered across the ranks (the same on every rank).
        let rows_across = model.thermal_active
            && split.iter().zip(&model.bodies).any(|(&s, body)| {
                s && matches!(body.source, BodySource::Mesh { mesh, .. }
                    if model.meshes[mesh as usize].joints.is_some())
            });
        let mut part = number(comm, local, particle_rows, rows_across);
        part.whole_bodies = whole;
        if model.has_particles() {
            part.locate_ghost_spheres(comm, model);
        }
        part.share_dirichlet(comm);
        Ok(part)
    }
}

/// Whether each body is split over the ranks: a body of its own mesh (not
/// a copy of a template, nor from a checkpoint) when there are several
/// ranks, in a mechanics run only if too large for the exact body
/// frequency of the explicit step (a small body's elements stay together
/// for it). A body with particles is split as any, its spheres cut with
/// its elements ([`super::spheres`]). A jointed body (issue 19), on all its
/// tets or on a set, is split too ([`make_bodies`]: its joints go to
/// every rank holding a tet at one of their corners).
fn split_bodies(model: &Model, size: usize) -> Vec<bool> {
    let mut users = vec![0usize; model.meshes.len()];
    for b in &model.bodies {
        if let BodySource::Mesh { mesh, .. } = b.source {
            users[mesh as usize] += 1;
        }
    }
    model
        .bodies
        .iter()
        .map(|b| match b.source {
            BodySource::Mesh { mesh, .. } => {
                size > 1
                    && users[mesh as usize] == 1
                    && (model.mechanics.is_none()
                        || (b.node_range.1 - b.node_range.0) as usize > BODY_EIGEN_MAX_NODES)
            }
            BodySource::Saved { .. } => false,
        })
        .collect()
}

/// The elements and nodes a rank has made, before numbering.
#[derive(Default)]
struct Made {
    /// Per element (ascending global id): id, body, material, face mask, node ids.
    elem_gid: Vec<u32>,
    elem_body: Vec<u32>,
    elem_material: Vec<u32>,
    face_mask: Vec<u8>,
    tets: Vec<[u32; 4]>,
    /// Per element, when any body is Hex8: each node's corner in its hex
    /// (`io::checkpoint_hexes`).
    hex_corner: Vec<[u8; 4]>,
    /// Per node (ascending global id, unique): id, position, boundary flag,
    /// and its conditions.
    node_gid: Vec<u32>,
    x: Vec<[f64; 3]>,
    boundary: Vec<bool>,
    initial_t: Vec<f64>,
    dirichlet: Vec<Option<f64>>,
    dirichlet_ramp: Vec<f64>,
    velocity: Vec<crate::mechanics::explicit::VelocityBc>,
    traction: Vec<[f64; 3]>,
    /// Faces with conditions (node ids).
    flux: Vec<([u32; 3], f64)>,
    convection: Vec<([u32; 3], f64, f64)>,
    /// Per node: whether it belongs to a split body.
    shared: Vec<bool>,
    /// Per node: a ghost only the joints across a cut need (a corner of
    /// another rank's tet), not a node of an element made here.
    joint_ghost: Vec<bool>,
    /// Joints of the jointed bodies (global node and element ids).
    joints: Vec<super::PartJoint>,
    /// Per joint: whether it ties thermal rows here (its body held whole).
    ties_rows: Vec<bool>,
    /// The nodes of jointed bodies split in a thermal run: each node's
    /// class (global id of the lowest copy tied to it by intact joints,
    /// [`super::tied_rows`]).
    class_of: HashMap<u32, u32>,
    /// The bonded particles here, per body with any.
    spheres: Vec<super::spheres::PartSpheres>,
}

/// Make the bodies and elements `held` by this rank.
fn make_bodies(
    model: &Model,
    files: &[crate::io::checkpoint::CheckpointFile],
    held: &std::collections::BTreeMap<u32, Held>,
) -> Result<Made> {
    let mech = model.mechanics.is_some();
    let any_hex = model.has_hexes();
    let mut m = Made::default();
    for (&b, h) in held {
        let body = &model.bodies[b as usize];
        let mesh = model
            .body_mesh(b as usize, files)
            .map_err(|message| Error::Model {
                path: body.name.clone(),
                message,
            })?;
        let (n0, e0) = (body.node_range.0, body.elem_range.0);
        // Elements, and after them (numbered from the elements' count) spheres.
        let ne = mesh.tets.len() as u32;
        let particles = model.body_particles(body);
        let (elems, own_spheres): (Vec<u32>, Vec<u32>) = match h {
            Held::Whole => (
                (0..ne).collect(),
                (0..particles.map_or(0, |p| p.region.centres.len() as u32)).collect(),
            ),
            Held::Elements(v) => {
                let k = v.partition_point(|&e| e < ne);
                (v[..k].to_vec(), v[k..].iter().map(|&s| s - ne).collect())
            }
        };
        // A jointed body: its jointed mesh around the elements held here
        // (issue 19), numbered locally; `gid` names its nodes, `slot` its
        // elements in it.
        let mut mesh = mesh;
        let (mut continuous, mut ids) = (None, None);
        if let Some((part, i)) = mesh.jointed_part(&elems) {
            continuous = Some(std::mem::replace(&mut mesh, part));
            ids = Some(i);
        }
        let gid = |n: u32| n0 + ids.as_ref().map_or(n, |i| i.copy[n as usize]);
        let slot = |e: u32| -> usize {
            ids.as_ref().map_or(e as usize, |i| {
                i.tet
                    .binary_search(&e)
                    .unwrap_or_else(|_| unreachable!("a held element is in its part"))
            })
        };
        let bc = model.body_bcs(b as usize, &mesh);
        let mut used = vec![false; mesh.nodes.len()];
        let mut face_of: HashMap<[u32; 3], ()> = HashMap::new();
        let whole = matches!(h, Held::Whole);
        // The corners of other ranks' tets that joints across the cut need.
        let mut wanted = vec![false; if whole { 0 } else { mesh.nodes.len() }];
        for &e in &elems {
            let i = slot(e);
            let t = mesh.tets[i];
            m.elem_gid.push(e0 + e);
            m.elem_body.push(b);
            m.elem_material.push(mesh.material[i]);
            m.face_mask.push(mesh.face_mask[i]);
            if any_hex {
                let hex = mesh.hexes.as_ref().map(|hx| &hx[e as usize / 6]);
                m.hex_corner.push(t.map(|n| {
                    hex.and_then(|hex| hex.iter().position(|&x| x == n))
                        .map_or(crate::io::checkpoint_hexes::NO_CORNER as u8, |k| k as u8)
                }));
            }
            m.tets.push(t.map(gid));
            for n in t {
                used[n as usize] = true;
            }
            if !whole {
                for k in 0..4 {
                    face_of.insert(crate::mesh::sorted_face(&t, k), ());
                }
            }
        }
        if let (Some(ids), Some(j)) = (&ids, continuous.as_ref().and_then(|c| c.joints.as_ref())) {
            // The joints at the copies here (a split body's: then every
            // joint at a node this rank may own is here, since a body
            // jointed on a set has continuum nodes that its joints share
            // with tets of other ranks). Their corners no tet here has
            // are ghosts.
            for &(k, f, broken) in &ids.joints {
                for &n in f.a.iter().chain(&f.b) {
                    if !whole && !used[n as usize] {
                        wanted[n as usize] = true;
                    }
                }
                m.joints.push(super::PartJoint {
                    faces: crate::fracture::insert::JointFaces {
                        a: f.a.map(gid),
                        b: f.b.map(gid),
                        tets: f.tets.map(|e| e0 + e),
                        area: f.area,
                    },
                    material: j.material,
                    broken,
                    body: b,
                    index: k,
                });
                m.ties_rows.push(whole);
            }
        }
        if let Some(p) = particles {
            let mut held = vec![false; mesh.tets.len()];
            elems.iter().for_each(|&e| held[e as usize] = true);
            let (s, want) = super::spheres::PartSpheres::select(
                b,
                &p.region,
                own_spheres,
                &held,
                &used,
                &mesh.tets,
            );
            if !whole {
                want.iter().for_each(|&n| wanted[n as usize] = true);
            }
            if !s.is_empty() {
                m.spheres.push(s);
            }
        }
        // A split body's copies by their class over the joints at their
        // vertices (those intact from the start).
        let classes = match (&continuous, &ids) {
            (Some(c), Some(ids)) if !whole && model.thermal_active => {
                let j = c.joints.as_ref().expect("a jointed body");
                let here: Vec<u32> = (0..mesh.nodes.len())
                    .filter(|&n| used[n] || wanted[n])
                    .map(|n| ids.copy[n])
                    .collect();
                let at = super::tied_rows::joints_at(j, &c.nodes, &here);
                super::tied_rows::local_classes(&here, &at, |k, _| !j.broken_at_start(k))
            }
            _ => HashMap::new(),
        };
        for (n, &u) in used.iter().enumerate() {
            let ghost = !u && wanted.get(n).copied().unwrap_or(false);
            if !u && !ghost {
                continue;
            }
            let g = gid(n as u32);
            if let Some(&c) = classes.get(&(g - n0)) {
                m.class_of.insert(g, n0 + c);
            }
            m.node_gid.push(g);
            m.x.push(mesh.nodes[n]);
            m.boundary.push(mesh.boundary_node[n]);
            m.initial_t.push(bc.initial_t[n]);
            m.dirichlet.push(bc.dirichlet[n]);
            m.dirichlet_ramp.push(bc.dirichlet_ramp[n]);
            if mech {
                m.velocity.push(bc.velocity[n]);
                m.traction.push(bc.traction[n]);
            }
            m.shared.push(!whole);
            m.joint_ghost.push(ghost);
        }
        let here = |f: &[u32; 3]| {
            whole || {
                let mut s = *f;
                s.sort_unstable();
                face_of.contains_key(&s)
            }
        };
        m.flux.extend(
            bc.flux
                .iter()
                .filter(|(f, _)| here(f))
                .map(|(f, q)| (f.map(gid), *q)),
        );
        m.convection.extend(
            bc.convection
                .iter()
                .filter(|(f, _, _)| here(f))
                .map(|(f, h, t)| (f.map(gid), *h, *t)),
        );
    }
    Ok(m)
}

/// The nodes tied by the intact joints of `joints` (global ids; each
/// pair of corners a[i], b[i] is one node of the continuous mesh while
/// the joint is intact), each mapped to the lowest id of its class.
fn joint_classes(joints: &[super::PartJoint]) -> HashMap<u32, u32> {
    crate::fracture::vertices::id_classes(
        joints
            .iter()
            .filter(|j| !j.broken)
            .flat_map(|j| j.faces.a.iter().copied().zip(j.faces.b.iter().copied())),
    )
}

/// Collective. The PETSc rows of this rank's owned nodes `owned` (global
/// ids, ascending): each its own row in order from this rank's start,
/// except that a node `tied` to a lower one takes that one's row (the
/// lowest of a class comes first); `extra` more rows (the particles')
/// end the rank's range. Returns every rank's start (and the total), the
/// row of each owned node, and the owned nodes tied to a lower one this
/// rank does not own (node, lowest), whose rows are another rank's.
#[allow(clippy::type_complexity)]
fn number_rows(
    comm: &SimpleCommunicator,
    owned: impl Iterator<Item = u32> + Clone,
    tied: &HashMap<u32, u32>,
    extra: usize,
) -> (Vec<usize>, HashMap<u32, u32>, Vec<(u32, u32)>) {
    let size = comm.size() as usize;
    let rank = comm.rank() as usize;
    let n_rows = owned
        .clone()
        .filter(|g| tied.get(g).is_none_or(|r| r == g))
        .count()
        + extra;
    let counts: Vec<u64> = all_gather(comm, &[n_rows as u64]);
    let mut starts = vec![0usize; size + 1];
    for r in 0..size {
        starts[r + 1] = starts[r] + counts[r] as usize;
    }
    let mut row_of: HashMap<u32, u32> = HashMap::new();
    let mut next = starts[rank] as u32;
    let mut elsewhere = Vec::new();
    for g in owned {
        let row = match tied.get(&g) {
            Some(&r) if r != g => match row_of.get(&r) {
                Some(&row) => row,
                None => {
                    elsewhere.push((g, r));
                    continue;
                }
            },
            _ => {
                next += 1;
                next - 1
            }
        };
        row_of.insert(g, row);
    }
    (starts, row_of, elsewhere)
}

/// Collective. Owners and PETSc numbers of the made nodes, and the part,
/// with `particle_rows` thermal rows of particles after its nodes';
/// `rows_across` (the same on every rank) when the copies of a split
/// jointed body tie rows across the ranks.
fn number(comm: &SimpleCommunicator, m: Made, particle_rows: usize, rows_across: bool) -> Part {
    let size = comm.size() as usize;
    let rank = comm.rank() as usize;
    // Owners of the split bodies' nodes: the lowest rank holding an
    // element of each (not a rank wanting it only for a joint across the
    // cut), found at the rendezvous rank gid % size.
    let mut ask: Vec<Vec<u32>> = vec![Vec::new(); size];
    for (i, &g) in m.node_gid.iter().enumerate() {
        if m.shared[i] {
            ask[g as usize % size].extend_from_slice(&[g, u32::from(m.joint_ghost[i])]);
        }
    }
    let asked = all_to_all(comm, ask);
    // Every rank asking for a node (holders and joint ghosts), and its owner.
    let mut holders: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut owner_at: HashMap<u32, u32> = HashMap::new();
    for (r, list) in asked.iter().enumerate() {
        for rec in list.chunks_exact(2) {
            holders.entry(rec[0]).or_default().push(r as u32);
            if rec[1] == 0 {
                let o = owner_at.entry(rec[0]).or_insert(r as u32);
                *o = (*o).min(r as u32);
            }
        }
    }
    let mut reply: Vec<Vec<u32>> = vec![Vec::new(); size];
    for (r, list) in asked.iter().enumerate() {
        for rec in list.chunks_exact(2) {
            let owner = owner_at[&rec[0]];
            reply[r].extend_from_slice(&[rec[0], owner]);
        }
    }
    let mut owner_of: HashMap<u32, u32> = HashMap::new();
    for rec in all_to_all(comm, reply)
        .iter()
        .flat_map(|v| v.chunks_exact(2))
    {
        owner_of.insert(rec[0], rec[1]);
    }
    let owner: Vec<u32> = m
        .node_gid
        .iter()
        .zip(&m.shared)
        .map(|(g, &s)| if s { owner_of[g] } else { rank as u32 })
        .collect();
    // PETSc numbers (the thermal rows): each rank's owned nodes in
    // ascending id from its start, the copies of a node that intact joints
    // tie (a jointed body, held whole here) sharing the row of the lowest.
    let n_owned = owner.iter().filter(|&&o| o as usize == rank).count();
    let tying: Vec<super::PartJoint> = m
        .joints
        .iter()
        .zip(&m.ties_rows)
        .filter(|(_, &t)| t)
        .map(|(j, _)| *j)
        .collect();
    let mut tied = joint_classes(&tying);
    tied.extend(m.class_of.iter().map(|(&g, &c)| (g, c)));
    let owned_gids = m
        .node_gid
        .iter()
        .zip(&owner)
        .filter(|(_, &o)| o as usize == rank)
        .map(|(&g, _)| g);
    let (starts, mut petsc_of, elsewhere) = number_rows(comm, owned_gids, &tied, particle_rows);
    if rows_across {
        super::tied_rows::fill_elsewhere(comm, &m.class_of, &mut petsc_of, elsewhere);
    }
    // Ghosts' numbers: owners tell the rendezvous rank, which tells the holders.
    let mut tell: Vec<Vec<u32>> = vec![Vec::new(); size];
    for (i, &g) in m.node_gid.iter().enumerate() {
        if m.shared[i] && owner[i] as usize == rank {
            tell[g as usize % size].extend_from_slice(&[g, petsc_of[&g]]);
        }
    }
    let mut forward: Vec<Vec<u32>> = vec![Vec::new(); size];
    for rec in all_to_all(comm, tell)
        .iter()
        .flat_map(|v| v.chunks_exact(2))
    {
        for &h in &holders[&rec[0]] {
            forward[h as usize].extend_from_slice(rec);
        }
    }
    for rec in all_to_all(comm, forward)
        .iter()
        .flat_map(|v| v.chunks_exact(2))
    {
        petsc_of.insert(rec[0], rec[1]);
    }
    // Local order: owned nodes ascending, then ghosts ascending.
    let mut order: Vec<usize> = (0..m.node_gid.len()).collect();
    order.sort_by_key(|&i| (owner[i] as usize != rank, m.node_gid[i]));
    let node_gid: Vec<u32> = order.iter().map(|&i| m.node_gid[i]).collect();
    let local: HashMap<u32, u32> = node_gid
        .iter()
        .enumerate()
        .map(|(l, &g)| (g, l as u32))
        .collect();
    let l = |g: u32| local[&g];
    let bc = LocalBcs {
        initial_t: order.iter().map(|&i| m.initial_t[i]).collect(),
        dirichlet: order
            .iter()
            .take(n_owned)
            .enumerate()
            .filter_map(|(li, &i)| m.dirichlet[i].map(|v| (li as u32, v)))
            .collect(),
        dirichlet_ramp: order
            .iter()
            .take(n_owned)
            .filter(|&&i| m.dirichlet[i].is_some())
            .map(|&i| m.dirichlet_ramp[i])
            .collect(),
        flux: m.flux.iter().map(|(f, q)| (f.map(l), *q)).collect(),
        convection: m
            .convection
            .iter()
            .map(|(f, h, t)| (f.map(l), *h, *t))
            .collect(),
        velocity: if m.velocity.is_empty() {
            Vec::new()
        } else {
            order.iter().map(|&i| m.velocity[i]).collect()
        },
        traction: if m.traction.is_empty() {
            Vec::new()
        } else {
            order.iter().take(n_owned).map(|&i| m.traction[i]).collect()
        },
    };
    Part {
        rank,
        size,
        mesh: TetMesh {
            nodes: order.iter().map(|&i| m.x[i]).collect(),
            tets: m.tets.iter().map(|t| t.map(l)).collect(),
            body: m.elem_body,
            ..Default::default()
        },
        elem_gid: m.elem_gid,
        elem_material: m.elem_material,
        face_mask: m.face_mask,
        hex_corner: m.hex_corner,
        node_owner: order.iter().map(|&i| owner[i]).collect(),
        petsc: node_gid.iter().map(|g| petsc_of[g]).collect(),
        boundary_node: order.iter().map(|&i| m.boundary[i]).collect(),
        node_gid,
        n_owned,
        starts,
        bc,
        whole: None,
        whole_bodies: Vec::new(),
        particle_rows,
        rows_across,
        own_dirichlet: None,
        spheres: m.spheres,
        joints: m
            .joints
            .iter()
            .map(|j| super::PartJoint {
                faces: crate::fracture::insert::JointFaces {
                    a: j.faces.a.map(l),
                    b: j.faces.b.map(l),
                    ..j.faces
                },
                ..*j
            })
            .collect(),
    }
}

impl Part {
    /// Collective. Number the PETSc rows again after joints broke: the
    /// copies of a node stay on one row only while intact joints (those
    /// whose two tets, by global id, are not in `broken`) still tie them,
    /// in the bodies held whole here (as [`Part::build`]: a split jointed
    /// body, in a run without a thermal problem, ties none). Every rank's
    /// start moves, so the ghosts of split bodies ask their owners for
    /// their new rows.
    pub fn renumber_rows(
        &mut self,
        comm: &SimpleCommunicator,
        model: &Model,
        broken: &std::collections::HashSet<[u32; 2]>,
    ) {
        let size = comm.size() as usize;
        let gid = |l: u32| self.node_gid[l as usize];
        let intact: Vec<super::PartJoint> = self
            .joints
            .iter()
            .filter(|j| {
                !broken.contains(&j.faces.tets) && self.whole_bodies.binary_search(&j.body).is_ok()
            })
            .map(|j| super::PartJoint {
                faces: crate::fracture::insert::JointFaces {
                    a: j.faces.a.map(gid),
                    b: j.faces.b.map(gid),
                    ..j.faces
                },
                ..*j
            })
            .collect();
        let mut tied = joint_classes(&intact);
        // A split jointed body's copies, tied across the ranks.
        let class_of = self.split_classes(comm, model, broken);
        tied.extend(class_of.iter().map(|(&g, &c)| (g, c)));
        let no = self.n_owned;
        let (starts, mut row_of, elsewhere) = number_rows(
            comm,
            self.node_gid[..no].iter().copied(),
            &tied,
            self.particle_rows,
        );
        if self.rows_across {
            super::tied_rows::fill_elsewhere(comm, &class_of, &mut row_of, elsewhere);
        }
        for l in 0..no {
            self.petsc[l] = row_of[&self.node_gid[l]];
        }
        // Ghosts: ask each owner.
        let mut ask: Vec<Vec<u32>> = vec![Vec::new(); size];
        for l in no..self.node_gid.len() {
            ask[self.node_owner[l] as usize].push(self.node_gid[l]);
        }
        let asked = all_to_all(comm, ask);
        let reply: Vec<Vec<u32>> = asked
            .iter()
            .map(|gids| gids.iter().map(|g| row_of[g]).collect())
            .collect();
        let answered = all_to_all(comm, reply);
        let mut at = vec![0usize; size];
        for l in no..self.node_gid.len() {
            let o = self.node_owner[l] as usize;
            self.petsc[l] = answered[o][at[o]];
            at[o] += 1;
        }
        self.starts = starts;
        self.share_dirichlet(comm);
    }
}
