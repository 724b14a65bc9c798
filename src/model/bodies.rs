//! Where each body's mesh comes from, and the body meshes themselves: a
//! mesh of its own (generated or read), a copy of a particle or lattice
//! template moved rigidly, or a body taken back from a checkpoint. Any
//! rank can make any body from the model (O(bodies) data plus the
//! templates), so each rank makes only the bodies it holds.

use nalgebra::{Matrix3, Vector3};

use crate::io::checkpoint::CheckpointFile;
use crate::mesh::TetMesh;

/// A mesh bodies are made from: a body's own, or a template shared by
/// the copies of a lattice or a pack. Its sets are unprefixed.
#[derive(Debug, Clone)]
pub struct SourceMesh {
    /// The mesh (body ids 0), at its place in the scenario.
    pub mesh: TetMesh,
    /// Material of every element (the body's, or a region's).
    pub material: Vec<u32>,
    /// Per element: its faces on the boundary (bit i: opposite node i).
    pub face_mask: Vec<u8>,
    /// Per node: on the boundary.
    pub boundary_node: Vec<bool>,
    /// The cohesive joints of a jointed mesh (issue 19).
    pub joints: Option<SourceJoints>,
    /// The particles of an element set taken out of the mesh (issue 21).
    pub particles: Option<super::particles::SourceParticles>,
    /// The hexes of a Hex8 mesh (issue 21): hex `h` is tets `6 h .. 6 h + 6`
    /// (`mesh::hex_tets`), over the mesh's nodes, seed 002 Table 1 order.
    pub hexes: Option<std::sync::Arc<[[u32; 8]]>>,
}

/// The joints of a source mesh made discontinuous (issue 19), kept as
/// the numbering of its copies and joints over the continuous mesh
/// ([`crate::fracture::numbering`]): a rank makes the copies and joints of
/// the tets it holds ([`BodyMesh::jointed_part`]), nothing of the whole
/// jointed body.
#[derive(Debug, Clone)]
pub struct SourceJoints {
    /// The numbering of the copies and joints.
    pub numbering: std::sync::Arc<crate::fracture::numbering::Numbering>,
    /// Per tet of the continuous mesh: made discontinuous.
    pub in_set: std::sync::Arc<[bool]>,
    /// The continuous mesh's tets (the numbering's mesh).
    pub tets: std::sync::Arc<[[u32; 4]]>,
    /// The fracture material (index into the model's materials).
    pub material: u32,
    /// The joints broken from the start (an initial crack), ascending.
    pub broken: Vec<u32>,
    /// How many node copies (the body's nodes) and joints.
    pub copies: u32,
    pub count: u32,
}

impl SourceJoints {
    /// The joints of `mesh` made discontinuous on the tets of `in_set`,
    /// of fracture material `material`, none broken.
    pub fn new(mesh: &TetMesh, in_set: &[bool], material: u32) -> SourceJoints {
        let numbering =
            crate::fracture::numbering::Numbering::new(mesh.nodes.len(), &mesh.tets, in_set);
        let (copies, count) = numbering.totals(&mesh.tets, in_set);
        SourceJoints {
            numbering: numbering.into(),
            in_set: in_set.into(),
            tets: mesh.tets.as_slice().into(),
            material,
            broken: Vec::new(),
            copies,
            count,
        }
    }

    /// Whether joint `k` is broken from the start.
    pub fn broken_at_start(&self, k: u32) -> bool {
        self.broken.binary_search(&k).is_ok()
    }

    /// The node of the continuous mesh copy `c` is a copy of.
    pub fn origin(&self, c: u32) -> u32 {
        self.numbering.origin(c, &self.tets, &self.in_set)
    }

    /// The copies of tet `t`'s corners.
    pub fn tet_copies(&self, t: u32) -> [u32; 4] {
        self.numbering.tet_copies(t, &self.tets, &self.in_set)
    }

    /// Every joint with a corner at a copy of one of the nodes `vertices`
    /// of the continuous mesh (at `nodes`): (number, faces).
    pub fn joints_at(
        &self,
        nodes: &[[f64; 3]],
        vertices: impl IntoIterator<Item = u32>,
    ) -> Vec<(u32, crate::fracture::insert::JointFaces)> {
        self.numbering
            .joints_at(nodes, &self.tets, &self.in_set, vertices)
    }
}

impl SourceMesh {
    /// A source mesh and its boundary.
    pub fn new(mesh: TetMesh, material: Vec<u32>) -> SourceMesh {
        let bt = crate::contact::BoundaryTets::new(&mesh);
        SourceMesh {
            face_mask: bt.mask,
            boundary_node: bt.boundary_node,
            material,
            mesh,
            joints: None,
            particles: None,
            hexes: None,
        }
    }

    /// A source mesh made discontinuous on the tets of `in_set`, tied by
    /// joints of fracture material `fracture`. It keeps the continuous
    /// mesh and its boundary (the joints' faces are not boundary faces
    /// while intact), and the numbering of the copies and joints.
    pub fn jointed(
        mesh: TetMesh,
        material: Vec<u32>,
        in_set: &[bool],
        fracture: u32,
    ) -> SourceMesh {
        let joints = SourceJoints::new(&mesh, in_set, fracture);
        SourceMesh {
            joints: Some(joints),
            ..SourceMesh::new(mesh, material)
        }
    }

    /// How many nodes the body has: the copies of a jointed mesh.
    pub fn node_count(&self) -> usize {
        self.joints
            .as_ref()
            .map_or(self.mesh.nodes.len(), |j| j.copies as usize)
    }

    /// The body nodes of element `e`'s corners (copies of a jointed mesh).
    pub fn tet_nodes(&self, e: usize) -> [u32; 4] {
        match &self.joints {
            None => self.mesh.tets[e],
            Some(j) => j.tet_copies(e as u32),
        }
    }

    /// The area of the largest joint (0 without joints).
    pub fn largest_joint_area(&self) -> f64 {
        self.joints.as_ref().map_or(0.0, |j| {
            crate::fracture::part_mesh::largest_joint_area(
                &self.mesh.nodes,
                &self.mesh.tets,
                &self.face_mask,
                &j.in_set,
            )
        })
    }

    /// Mark broken the joints whose faces lie in the plane through `point`
    /// with normal `normal` (every corner within 1e-6 of the face's size
    /// of it): an initial crack. Returns how many.
    pub fn break_on_plane(&mut self, point: [f64; 3], normal: [f64; 3]) -> usize {
        let Some(j) = &mut self.joints else { return 0 };
        let len = normal.iter().map(|c| c * c).sum::<f64>().sqrt();
        let n = normal.map(|c| c / len);
        let nodes = &self.mesh.nodes;
        let off = |v: u32| {
            let x = nodes[v as usize];
            (0..3).map(|d| (x[d] - point[d]) * n[d]).sum::<f64>().abs()
        };
        let mut broken = Vec::new();
        j.numbering
            .for_each_joint(&self.mesh.tets, &j.in_set, |k, corners| {
                let p = corners.map(|v| nodes[v as usize]);
                let tol = 1e-6 * crate::geometry::polygon_area(&p).sqrt();
                if corners.iter().all(|&v| off(v) <= tol) {
                    broken.push(k);
                }
            });
        let count = broken.len();
        j.broken.extend(broken);
        j.broken.sort_unstable();
        j.broken.dedup();
        count
    }
}

/// How one body's nodes are made.
#[derive(Debug, Clone, PartialEq)]
pub enum BodySource {
    /// Source mesh `mesh`, its nodes x moved to `site + R (x − center)`
    /// (a pack's particle) or translated by `offset` (a lattice copy, or a
    /// body's own mesh with a zero offset).
    Mesh {
        /// Index into [`crate::model::Model::meshes`].
        mesh: u32,
        /// The rigid motion.
        motion: Motion,
    },
    /// Body `body` of checkpoint file `file`, translated by `offset`.
    Saved {
        /// Index into [`crate::model::Model::checkpoints`].
        file: u32,
        /// The body's index in that checkpoint.
        body: u32,
        /// Translation (m).
        offset: [f64; 3],
        /// Made discontinuous at load, every tet jointed (issue 19).
        joints: Option<SavedJoints>,
        /// A Hex8 body (issue 21): its hexes come from the file's hex
        /// corners (`io::checkpoint_hexes`).
        hex8: bool,
    },
}

/// The joints of a checkpoint body jointed at load: every face two of its
/// tets share. What the model keeps of them is O(1) per body; the joints
/// themselves are made by the rank that holds the body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SavedJoints {
    /// Fracture material (index into the model's materials).
    pub material: u32,
    /// How many joints the body has.
    pub count: u64,
}

/// A rigid motion of a source mesh's nodes.
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// x + offset.
    Translate([f64; 3]),
    /// site + R (x − center).
    Place {
        /// Rotation.
        rotation: Matrix3<f64>,
        /// The point of the template that goes to `site`.
        center: Vector3<f64>,
        /// Where it goes.
        site: Vector3<f64>,
    },
}

impl Motion {
    /// The moved point.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        match self {
            Motion::Translate(t) => [p[0] + t[0], p[1] + t[1], p[2] + t[2]],
            Motion::Place {
                rotation,
                center,
                site,
            } => {
                let q = site + rotation * (Vector3::from(p) - center);
                [q.x, q.y, q.z]
            }
        }
    }
}

/// A body's mesh as a rank makes it: its nodes (body-local numbering),
/// elements, materials, boundary, and the named sets of its source.
#[derive(Debug, Clone)]
pub struct BodyMesh<'a> {
    /// Node positions (reference configuration).
    pub nodes: Vec<[f64; 3]>,
    /// Elements over the body's nodes.
    pub tets: std::borrow::Cow<'a, [[u32; 4]]>,
    /// Material of every element.
    pub material: std::borrow::Cow<'a, [u32]>,
    /// Per element: its faces on the boundary.
    pub face_mask: std::borrow::Cow<'a, [u8]>,
    /// Per node: on the boundary.
    pub boundary_node: std::borrow::Cow<'a, [bool]>,
    /// The source mesh, for its named sets (none for a checkpoint body).
    pub source: Option<std::borrow::Cow<'a, TetMesh>>,
    /// Its joints, if jointed: then the mesh above is the continuous one,
    /// and [`BodyMesh::jointed_part`] makes the jointed one around a part.
    pub joints: Option<std::borrow::Cow<'a, SourceJoints>>,
    /// Its hexes if Hex8 (issue 21): hex `h` is tets `6 h .. 6 h + 6`.
    pub hexes: Option<std::borrow::Cow<'a, [[u32; 8]]>>,
}

/// How the jointed mesh around a part ([`BodyMesh::jointed_part`]) names
/// the body's nodes, elements and joints.
#[derive(Debug, Clone)]
pub struct JointedIds {
    /// Per node: its node of the body (a copy).
    pub copy: Vec<u32>,
    /// Per element: its element of the body.
    pub tet: Vec<u32>,
    /// The joints at the copies of the held tets (ascending number), with
    /// corners in the part's numbering, and whether broken from the start.
    pub joints: Vec<(u32, crate::fracture::insert::JointFaces, bool)>,
}

impl BodyMesh<'_> {
    /// A jointed body's mesh made discontinuous around its elements
    /// `held` (ascending; all of them for a body held whole): the copies
    /// they and their joints need, the ring of elements at those copies
    /// (so that the named sets reach them as in the whole-body build),
    /// with their materials, boundary and sets, and how they are named in
    /// the body. `None` for a body without joints.
    pub fn jointed_part(&self, held: &[u32]) -> Option<(BodyMesh<'static>, JointedIds)> {
        use std::borrow::Cow;
        let j = self.joints.as_ref()?;
        let p = crate::fracture::part_mesh::JointedPart::new(
            &j.numbering,
            (
                &self.nodes,
                self.source.as_deref().map_or(&self.nodes, |s| &s.nodes),
            ),
            &self.tets,
            self.source.as_deref(),
            &j.in_set,
            held,
        );
        let mesh = BodyMesh {
            nodes: p.mesh.nodes.clone(),
            tets: Cow::Owned(p.mesh.tets.clone()),
            material: Cow::Owned(p.tet.iter().map(|&t| self.material[t as usize]).collect()),
            face_mask: Cow::Owned(p.tet.iter().map(|&t| self.face_mask[t as usize]).collect()),
            boundary_node: Cow::Owned(
                p.origin
                    .iter()
                    .map(|&g| self.boundary_node[g as usize])
                    .collect(),
            ),
            source: Some(Cow::Owned(p.mesh)),
            joints: None,
            hexes: None,
        };
        let joints = p
            .joints
            .into_iter()
            .map(|(k, f)| (k, f, j.broken_at_start(k)))
            .collect();
        Some((
            mesh,
            JointedIds {
                copy: p.copy,
                tet: p.tet,
                joints,
            },
        ))
    }
}

impl super::Model {
    /// The mesh of body `b`: its source moved into place, or its rows of a
    /// checkpoint (`files` open, indexed as [`super::Model::checkpoints`]).
    pub fn body_mesh<'a>(
        &'a self,
        b: usize,
        files: &[CheckpointFile],
    ) -> Result<BodyMesh<'a>, String> {
        match &self.bodies[b].source {
            BodySource::Mesh { mesh, motion } => {
                let src = &self.meshes[*mesh as usize];
                Ok(BodyMesh {
                    nodes: src.mesh.nodes.iter().map(|&p| motion.apply(p)).collect(),
                    tets: std::borrow::Cow::Borrowed(&src.mesh.tets),
                    material: std::borrow::Cow::Borrowed(&src.material),
                    face_mask: std::borrow::Cow::Borrowed(&src.face_mask),
                    boundary_node: std::borrow::Cow::Borrowed(&src.boundary_node),
                    source: Some(std::borrow::Cow::Borrowed(&src.mesh)),
                    joints: src.joints.as_ref().map(std::borrow::Cow::Borrowed),
                    hexes: src.hexes.as_deref().map(std::borrow::Cow::Borrowed),
                })
            }
            BodySource::Saved {
                file,
                body,
                offset,
                joints,
                hex8,
            } => {
                let f = &files[*file as usize];
                let m = saved_mesh(f, *body, *offset)?;
                let hexes = if *hex8 {
                    Some(saved_hexes(f, *body, &m.tets)?)
                } else {
                    None
                };
                let material = vec![self.bodies[b].material as u32; m.tets.len()];
                let src = match joints {
                    None => SourceMesh::new(m, material),
                    Some(j) => {
                        let all = vec![true; m.tets.len()];
                        let src = SourceMesh::jointed(m, material, &all, j.material);
                        let made = src.joints.as_ref().map_or(0, |s| u64::from(s.count));
                        if made != j.count {
                            return Err(format!(
                                "{}: body `{}` has {made} joints, {} when the model was made \
                                 (the file changed during the run?)",
                                f.path().display(),
                                f.head.body_names[*body as usize],
                                j.count
                            ));
                        }
                        src
                    }
                };
                Ok(BodyMesh {
                    nodes: src.mesh.nodes,
                    tets: std::borrow::Cow::Owned(src.mesh.tets),
                    material: std::borrow::Cow::Owned(src.material),
                    face_mask: std::borrow::Cow::Owned(src.face_mask),
                    boundary_node: std::borrow::Cow::Owned(src.boundary_node),
                    source: None,
                    joints: src.joints.map(std::borrow::Cow::Owned),
                    hexes: hexes.map(std::borrow::Cow::Owned),
                })
            }
        }
    }

    /// Whether any body is jointed (issue 19).
    pub fn has_joints(&self) -> bool {
        self.meshes.iter().any(|m| m.joints.is_some())
            || self.bodies.iter().any(|b| {
                matches!(
                    b.source,
                    BodySource::Saved {
                        joints: Some(_),
                        ..
                    }
                )
            })
    }

    /// The corners (global node ids, in the element's order) and material
    /// of element `elem` (global id) of body `b`, a body of its own source
    /// mesh (a split jointed body's).
    pub fn element_corners(&self, b: usize, elem: u32) -> ([u32; 4], u32) {
        let body = &self.bodies[b];
        let BodySource::Mesh { mesh, .. } = body.source else {
            unreachable!("a split body has its own source mesh")
        };
        let src = &self.meshes[mesh as usize];
        let e = (elem - body.elem_range.0) as usize;
        (
            src.tet_nodes(e).map(|n| body.node_range.0 + n),
            src.material[e],
        )
    }

    /// The hex element global id `elem` belongs to (issue 21), if its
    /// body is a Hex8 mesh: the global id of the hex's first tet and its
    /// eight global node ids (seed 002 Table 1 order).
    pub fn element_hex(&self, elem: u32) -> Option<(u32, [u32; 8])> {
        let body = &self.bodies[self.body_of_elem(elem)];
        let BodySource::Mesh { mesh, .. } = body.source else {
            return None;
        };
        let hexes = self.meshes[mesh as usize].hexes.as_ref()?;
        let h = (elem - body.elem_range.0) / 6;
        Some((
            body.elem_range.0 + 6 * h,
            hexes[h as usize].map(|n| body.node_range.0 + n),
        ))
    }

    /// How many elements are a Hex8's tets (six per hex, issue 21).
    pub fn hex_tets(&self) -> u64 {
        (0..self.bodies.len())
            .filter(|&b| self.body_is_hex8(b))
            .map(|b| u64::from(self.bodies[b].elem_range.1 - self.bodies[b].elem_range.0))
            .sum()
    }

    /// Whether body `b` is a Hex8 mesh (issue 21), of its own source or
    /// from a checkpoint.
    pub fn body_is_hex8(&self, b: usize) -> bool {
        match self.bodies[b].source {
            BodySource::Mesh { mesh, .. } => self.meshes[mesh as usize].hexes.is_some(),
            BodySource::Saved { hex8, .. } => hex8,
        }
    }

    /// Whether any body is Hex8 (the same on every rank).
    pub fn has_hexes(&self) -> bool {
        (0..self.bodies.len()).any(|b| self.body_is_hex8(b))
    }

    /// Per body, the global number of its first joint (joints numbered
    /// body by body, each body's in its mesh's joint order), and the
    /// total: O(bodies), the same on every rank.
    pub fn joint_offsets(&self) -> (Vec<u64>, u64) {
        let mut next = 0u64;
        let offsets = self
            .bodies
            .iter()
            .map(|b| {
                let at = next;
                next += match b.source {
                    BodySource::Mesh { mesh, .. } => self.meshes[mesh as usize]
                        .joints
                        .as_ref()
                        .map_or(0, |j| u64::from(j.count)),
                    BodySource::Saved { joints, .. } => joints.map_or(0, |j| j.count),
                };
                at
            })
            .collect();
        (offsets, next)
    }

    /// Open the checkpoint files the bodies come from (every rank reads
    /// their heads; rows on demand).
    pub fn open_checkpoints(&self) -> crate::error::Result<Vec<CheckpointFile>> {
        self.checkpoints
            .iter()
            .map(|p| {
                CheckpointFile::open(p).map_err(|e| crate::error::Error::Model {
                    path: p.display().to_string(),
                    message: e.to_string(),
                })
            })
            .collect()
    }

    /// The mean of a body's node positions (its place for partitioning),
    /// without making its mesh for a source-mesh body.
    pub fn body_center(&self, b: usize, files: &[CheckpointFile]) -> Result<[f64; 3], String> {
        match &self.bodies[b].source {
            BodySource::Mesh { mesh, motion } => {
                Ok(motion.apply(self.meshes[*mesh as usize].mean_node()))
            }
            BodySource::Saved {
                file, body, offset, ..
            } => Ok(mean(
                &saved_mesh(&files[*file as usize], *body, *offset)?.nodes,
            )),
        }
    }
}

/// Body `body` of checkpoint `f` as it was saved (its positions if the
/// file has them, else its reference), translated by `offset`, checked.
pub(super) fn saved_mesh(
    f: &CheckpointFile,
    body: u32,
    offset: [f64; 3],
) -> Result<TetMesh, String> {
    let h = &f.head;
    let [n0, n1] = h.body_nodes[body as usize];
    let [e0, e1] = h.body_elems[body as usize];
    let ids: Vec<u32> = (n0..n1).collect();
    let name = if h.has_positions {
        "state/positions"
    } else {
        "mesh/reference"
    };
    let err = |e: crate::io::IoError| e.to_string();
    let x = f.node_rows3(name, &ids).map_err(err)?;
    let tets = f.elem_tets(&(e0..e1).collect::<Vec<u32>>()).map_err(err)?;
    let mut m = TetMesh {
        nodes: x
            .iter()
            .map(|p| [p[0] + offset[0], p[1] + offset[1], p[2] + offset[2]])
            .collect(),
        tets: Vec::with_capacity(tets.len()),
        body: vec![0; tets.len()],
        ..Default::default()
    };
    for (e, t) in tets.iter().enumerate() {
        if t.iter().any(|&n| n < n0 || n >= n1) {
            return Err(format!(
                "{}: element {} of body `{}` names a node outside the body",
                f.path().display(),
                e0 as usize + e,
                h.body_names[body as usize]
            ));
        }
        m.tets.push(t.map(|n| n - n0));
    }
    m.validate().map_err(|e| {
        format!(
            "{}: body `{}`: {e}",
            f.path().display(),
            h.body_names[body as usize]
        )
    })?;
    Ok(m)
}

impl SourceMesh {
    /// The mean of the node positions (of a jointed mesh's copies).
    pub fn mean_node(&self) -> [f64; 3] {
        let Some(j) = &self.joints else {
            return mean(&self.mesh.nodes);
        };
        let mut s = [0.0; 3];
        for (n, p) in self.mesh.nodes.iter().enumerate() {
            let k = f64::from(j.numbering.copies_of(n as u32, &j.in_set));
            (0..3).for_each(|d| s[d] += k * p[d]);
        }
        s.map(|x| x / f64::from(j.copies.max(1)))
    }
}

fn mean(nodes: &[[f64; 3]]) -> [f64; 3] {
    let n = nodes.len().max(1) as f64;
    let s = nodes
        .iter()
        .fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
    [s[0] / n, s[1] / n, s[2] / n]
}

/// The hexes of Hex8 body `body` of checkpoint `f`, whose tets (body-local
/// node numbers) are `tets`, from the file's hex corners.
fn saved_hexes(f: &CheckpointFile, body: u32, tets: &[[u32; 4]]) -> Result<Vec<[u32; 8]>, String> {
    let h = &f.head;
    let [e0, e1] = h.body_elems[body as usize];
    let corners = f
        .elem_hex_corner(&(e0..e1).collect::<Vec<u32>>())
        .map_err(|e| e.to_string())?;
    crate::io::checkpoint_hexes::hexes_from_corners(tets, &corners).map_err(|e| {
        format!(
            "{}: Hex8 body `{}` (its elements from {e0}): {e}",
            f.path().display(),
            h.body_names[body as usize]
        )
    })
}

/// The elements of the set `set` of a body's mesh, or an error naming the
/// body, the scenario key and the sets the mesh has.
pub(super) fn elements_of<'m>(
    m: &'m TetMesh,
    set: &str,
    body: &str,
    key: &str,
) -> Result<&'m [u32], String> {
    m.elem_sets.get(set).map(Vec::as_slice).ok_or_else(|| {
        let names: Vec<&str> = m.elem_sets.keys().map(String::as_str).collect();
        format!(
            "body `{body}`: {key}: no element set `{set}` in its mesh; available: {}",
            names.join(", ")
        )
    })
}
