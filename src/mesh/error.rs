//! Error type of the mesh module ([`MeshError`]).
//!
//! Every variant names what is wrong: the file (and line, byte offset or
//! section) for Gmsh import/export, the element (0-based index, plus the Gmsh
//! element tag when the mesh was imported) or node for geometry errors, and
//! the set name for set errors.

use std::path::PathBuf;

/// Errors produced by mesh validation, generation and Gmsh import/export.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The mesh file could not be read (missing, permissions, ...).
    #[error("cannot read mesh file '{}': {source}", .path.display())]
    Read {
        /// File that was being read.
        path: PathBuf,
        /// Underlying I/O error.
        #[source]
        source: std::io::Error,
    },

    /// The mesh file could not be written.
    #[error("cannot write mesh file '{}': {source}", .path.display())]
    Write {
        /// File that was being written.
        path: PathBuf,
        /// Underlying I/O error.
        #[source]
        source: std::io::Error,
    },

    /// The Gmsh file is syntactically malformed (reported by mshio or by the
    /// `$MeshFormat`/`$PhysicalNames`/`$Nodes` pre-scans of this module).
    #[error("'{}': malformed Gmsh file{}: {message}", .path.display(), location_note(.location))]
    MalformedGmsh {
        /// File that was being read.
        path: PathBuf,
        /// Where the problem is, e.g. `line 12 (section $Nodes)` or `byte offset 345`.
        location: Option<String>,
        /// What is wrong.
        message: String,
    },

    /// The file is not in MSH 4.1 format.
    #[error(
        "'{}': MSH format version {version} is not supported; MSH 4.1 is required \
         (export with `gmsh -format msh41` or set `Mesh.MshFileVersion = 4.1;`)",
        .path.display()
    )]
    UnsupportedVersion {
        /// File that was being read.
        path: PathBuf,
        /// Version string found in `$MeshFormat`.
        version: String,
    },

    /// A 3D element of a type the reader does not take (a Tet4 reader meets
    /// a hexahedron, a Hex8 reader a prism, either a quadratic element).
    #[error(
        "'{}': element with gmsh tag {gmsh_tag} (volume entity {entity}) has Gmsh type \
         {type_code} ({type_name}); only {supported} are supported",
        .path.display()
    )]
    UnsupportedElement {
        /// File that was being read.
        path: PathBuf,
        /// Gmsh tag of the first offending element.
        gmsh_tag: u64,
        /// Gmsh entity tag of the element block.
        entity: i32,
        /// Gmsh element type code.
        type_code: i32,
        /// mshio's name of the element type (e.g. `Tet10`).
        type_name: String,
        /// What the reader takes, e.g. `linear tetrahedra (Gmsh type 4)`.
        supported: &'static str,
    },

    /// The Gmsh file is well-formed but its content cannot be turned into a
    /// [`TetMesh`](super::TetMesh) (unknown node tags, triangles that are not
    /// boundary faces, no tetrahedra, ...).
    #[error("'{}': {message}", .path.display())]
    InvalidGmsh {
        /// File that was being read or written.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },

    /// A geometry/consistency error found while importing a file.
    #[error("'{}': {source}", .path.display())]
    InFile {
        /// File that was being read.
        path: PathBuf,
        /// The mesh error (element indices refer to the imported mesh).
        #[source]
        source: Box<MeshError>,
    },

    /// A node has a NaN or infinite coordinate.
    #[error("node {node} has a non-finite coordinate ({}, {}, {})", .coords[0], .coords[1], .coords[2])]
    NonFiniteNode {
        /// 0-based node index.
        node: u32,
        /// The coordinates.
        coords: [f64; 3],
    },

    /// An element refers to a node index that does not exist.
    #[error(
        "element {elem}{} refers to node {node}, but the mesh has only {num_nodes} nodes",
        tag_note(.gmsh_tag)
    )]
    NodeOutOfRange {
        /// 0-based element index.
        elem: usize,
        /// Gmsh element tag, when imported.
        gmsh_tag: Option<u64>,
        /// The offending node index.
        node: u32,
        /// Number of nodes in the mesh.
        num_nodes: usize,
    },

    /// An element has negative signed volume (nodes 2 and 3 swapped, or a
    /// mesher using the opposite orientation convention).
    #[error(
        "element {elem}{} is inverted: signed volume {volume:.3e} m^3 ({})",
        tag_note(.gmsh_tag),
        list_nodes(.nodes, .gmsh_nodes)
    )]
    Inverted {
        /// 0-based element index.
        elem: usize,
        /// Gmsh element tag, when imported.
        gmsh_tag: Option<u64>,
        /// Signed volume (negative).
        volume: f64,
        /// Node indices of the element.
        nodes: [u32; 4],
        /// Gmsh node tags of the element, when imported.
        gmsh_nodes: Option<[u64; 4]>,
    },

    /// An element has (nearly) zero volume: |V| <= 1e-12 * (longest edge)^3.
    #[error(
        "element {elem}{} is degenerate: volume {volume:.3e} m^3, longest edge {longest_edge:.3e} m ({})",
        tag_note(.gmsh_tag),
        list_nodes(.nodes, .gmsh_nodes)
    )]
    Degenerate {
        /// 0-based element index.
        elem: usize,
        /// Gmsh element tag, when imported.
        gmsh_tag: Option<u64>,
        /// Signed volume.
        volume: f64,
        /// Longest edge length.
        longest_edge: f64,
        /// Node indices of the element.
        nodes: [u32; 4],
        /// Gmsh node tags of the element, when imported.
        gmsh_nodes: Option<[u64; 4]>,
    },

    /// `body.len() != tets.len()`.
    #[error("the body vector has {body_len} entries but the mesh has {num_elems} elements")]
    BodyLength {
        /// Length of `body`.
        body_len: usize,
        /// Length of `tets`.
        num_elems: usize,
    },

    /// A named set refers to a node, element or face node that does not exist.
    #[error("{kind} set '{name}' refers to {item} {index}, but the mesh has only {count} {item}s")]
    SetOutOfRange {
        /// `node`, `element` or `face`.
        kind: &'static str,
        /// Name of the set.
        name: String,
        /// `node` or `element`.
        item: &'static str,
        /// The offending index.
        index: u32,
        /// Number of nodes or elements.
        count: usize,
    },

    /// A generator argument is invalid (non-positive or non-finite size, ...).
    #[error("invalid mesh parameter: {0}")]
    InvalidParameter(String),

    /// The mesh is not a single closed volume
    /// ([`TetMesh::check_closed_volume`](super::TetMesh::check_closed_volume)):
    /// no elements, a non-manifold boundary edge, several unconnected
    /// pieces, or a boundary that does not enclose the element volume.
    #[error("mesh is not a closed volume: {message}")]
    NotClosed {
        /// What is wrong (names the offending edge, piece count or volumes).
        message: String,
    },

    /// The mesh would exceed the `u32` index range or
    /// [`MAX_ELEMENTS`](super::MAX_ELEMENTS) elements.
    #[error("mesh too large: {0}")]
    TooLarge(String),
}

fn location_note(location: &Option<String>) -> String {
    match location {
        Some(l) => format!(" at {l}"),
        None => String::new(),
    }
}

fn tag_note(tag: &Option<u64>) -> String {
    match tag {
        Some(t) => format!(" (gmsh tag {t})"),
        None => String::new(),
    }
}

/// The element's nodes: Gmsh node tags for an imported mesh (the numbers
/// the user's file shows), else 0-based node indices.
fn list_nodes(nodes: &[u32; 4], gmsh: &Option<[u64; 4]>) -> String {
    match gmsh {
        Some(t) => format!("gmsh node tags {},{},{},{}", t[0], t[1], t[2], t[3]),
        None => format!("nodes {},{},{},{}", nodes[0], nodes[1], nodes[2], nodes[3]),
    }
}
