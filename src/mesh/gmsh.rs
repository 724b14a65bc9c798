//! Gmsh MSH 4.1 import (ASCII and binary, parsed by `mshio`) and ASCII export.
//!
//! # Import ([`read_msh`], [`read_msh_with`])
//! * Only linear tetrahedra (Gmsh type 4) become elements; any other 3D
//!   element type (Tet10, hexahedra, ...) is an error.
//! * Elements are ordered by ascending Gmsh element tag, nodes by ascending
//!   Gmsh node tag; only nodes used by tetrahedra or node sets are kept and
//!   renumbered 0-based contiguously.
//! * Physical volumes become element sets. Body ids: the physical volumes
//!   that contain tetrahedra, sorted by physical tag, get body ids 0, 1, ...;
//!   a tetrahedron in several physical volumes gets the body of the lowest
//!   tag. Without physical volumes every tetrahedron is body 0; if physical
//!   volumes exist, tetrahedra outside all of them are an error.
//! * Triangles (type 2) of physical surfaces become face sets, re-oriented
//!   outward using the owning tetrahedron; a triangle that is not a boundary
//!   face of the tetrahedral mesh is an error. Duplicate triangles in a set
//!   are dropped.
//! * Nodes of elements of physical points and curves become node sets.
//! * Group names come from `$PhysicalNames`; unnamed groups are called
//!   `physical_<dim>_<tag>`. Groups with the same name and kind are merged.
//! * Inverted or degenerate tetrahedra are errors naming the Gmsh tag,
//!   unless [`ReadOptions::fix_orientation`] is set (inverted ones are then
//!   repaired by swapping local nodes 2 and 3).
//!
//! mshio does not parse `$PhysicalNames`, so this module reads that (always
//! ASCII) section itself. mshio also drops node tags when the file's node
//! tags are dense (`max - min + 1 == count`); they are then re-read from the
//! `$Nodes` section by a small scanner here, so dense tags in any block
//! order are handled correctly.
//!
//! # Hex8 import ([`read_msh_hex8`])
//! 8-node hexahedra for the FE–DE kernels, on the same parsing and errors;
//! see the `hex` submodule.
//!
//! # Export ([`write_msh_ascii`])
//! Writes MSH 4.1 ASCII: one volume entity and physical volume per body,
//! one surface entity and physical surface per face set, `$PhysicalNames`.
//! See [`write_msh_ascii`] for what survives a round trip.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet};
use std::fmt::Write as _;
use std::path::Path;

use mshio::{ElementType, MshFile};

use super::{MeshError, TetMesh};

/// Options for [`read_msh_with`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// Repair inverted tetrahedra (negative signed volume) by swapping their
    /// local nodes 2 and 3 instead of reporting an error. Default: `false`.
    pub fix_orientation: bool,
}

/// Reads a Gmsh MSH 4.1 file (ASCII or binary) with default
/// [`ReadOptions`]. See the [module documentation](self) for the mapping of
/// Gmsh entities and physical groups.
pub fn read_msh(path: &Path) -> Result<TetMesh, MeshError> {
    read_msh_with(path, &ReadOptions::default())
}

/// Reads a Gmsh MSH 4.1 file (ASCII or binary).
///
/// Errors name the file, and where possible the line (ASCII) or byte offset
/// (binary), the Gmsh element tag or the physical group.
pub fn read_msh_with(path: &Path, opts: &ReadOptions) -> Result<TetMesh, MeshError> {
    let bytes = read_bytes(path)?;
    let reader = Reader {
        path,
        bytes: &bytes,
    };
    reader.read(opts)
}

/// The bytes of the file at `path`.
fn read_bytes(path: &Path) -> Result<Vec<u8>, MeshError> {
    std::fs::read(path).map_err(|source| MeshError::Read {
        path: path.to_path_buf(),
        source,
    })
}

/// Layout of the file as given by `$MeshFormat`.
#[derive(Debug, Clone, Copy)]
struct Format {
    binary: bool,
    size_t: usize,
    big_endian: bool,
}

/// A parsed file: mshio's data plus what this module reads itself.
struct Parsed {
    msh: MshFile<u64, i32, f64>,
    /// `$PhysicalNames`: (dim, physical tag) -> name.
    names: HashMap<(i32, i32), String>,
    fmt: Format,
}

/// The nodes kept by [`Reader::compact_nodes`].
struct CompactNodes {
    nodes: Vec<[f64; 3]>,
    /// Gmsh tag of each kept node.
    tags: Vec<u64>,
    /// New index per index of the tag-sorted list (`u32::MAX`: dropped).
    new_id: Vec<u32>,
}

/// Name of physical group (dim, tag): from `$PhysicalNames`, else
/// `physical_<dim>_<tag>`.
fn group_name(names: &HashMap<(i32, i32), String>, dim: i32, tag: i32) -> String {
    names
        .get(&(dim, tag))
        .cloned()
        .unwrap_or_else(|| format!("physical_{dim}_{tag}"))
}

/// Physical tags per (entity dim, entity tag).
fn physical_tags(msh: &MshFile<u64, i32, f64>) -> HashMap<(i32, i32), Vec<i32>> {
    let mut phys = HashMap::new();
    if let Some(ent) = &msh.data.entities {
        for p in &ent.points {
            phys.insert((0, p.tag), p.physical_tags.clone());
        }
        for c in &ent.curves {
            phys.insert((1, c.tag), c.physical_tags.clone());
        }
        for s in &ent.surfaces {
            phys.insert((2, s.tag), s.physical_tags.clone());
        }
        for v in &ent.volumes {
            phys.insert((3, v.tag), v.physical_tags.clone());
        }
    }
    phys
}

struct Reader<'a> {
    path: &'a Path,
    bytes: &'a [u8],
}

/// Finds `needle` at the start of a line, followed by a line break, at or after `from`.
fn find_line(hay: &[u8], needle: &[u8], from: usize) -> Option<usize> {
    let mut start = from;
    while start + needle.len() <= hay.len() {
        let rel = hay[start..]
            .windows(needle.len())
            .position(|w| w == needle)?;
        let p = start + rel;
        let at_line_start = p == 0 || hay[p - 1] == b'\n';
        let rest = &hay[p + needle.len()..];
        let line_end = rest.starts_with(b"\n") || rest.starts_with(b"\r\n");
        if at_line_start && line_end {
            return Some(p);
        }
        start = p + 1;
    }
    None
}

/// 1-based line number of byte `offset`.
fn line_of(bytes: &[u8], offset: usize) -> usize {
    1 + bytes[..offset.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// Splits off the next line (without the line break); returns (line, rest).
fn next_line(b: &[u8]) -> (&[u8], &[u8]) {
    match b.iter().position(|&c| c == b'\n') {
        Some(p) => {
            let line = &b[..p];
            let line = line.strip_suffix(b"\r").unwrap_or(line);
            (line, &b[p + 1..])
        }
        None => (b, &b[b.len()..]),
    }
}

impl<'a> Reader<'a> {
    fn malformed(&self, offset: Option<usize>, binary: bool, message: String) -> MeshError {
        let location = offset.map(|o| {
            if binary {
                format!("byte offset {o}")
            } else {
                let line = line_of(self.bytes, o);
                match self.section_at(o) {
                    Some(s) => format!("line {line} (section {s})"),
                    None => format!("line {line}"),
                }
            }
        });
        MeshError::MalformedGmsh {
            path: self.path.to_path_buf(),
            location,
            message,
        }
    }

    fn invalid(&self, message: String) -> MeshError {
        MeshError::InvalidGmsh {
            path: self.path.to_path_buf(),
            message,
        }
    }

    /// Name of the last section header (`$Name`) at or before `offset` (ASCII files).
    fn section_at(&self, offset: usize) -> Option<String> {
        let b = &self.bytes[..offset.min(self.bytes.len())];
        let mut p = b.len();
        loop {
            let nl = b[..p].iter().rposition(|&c| c == b'\n');
            let line_start = nl.map_or(0, |n| n + 1);
            if self.bytes.get(line_start) == Some(&b'$') {
                let (line, _) = next_line(&self.bytes[line_start..]);
                let name = String::from_utf8_lossy(line).trim().to_string();
                return Some(name);
            }
            p = nl?;
        }
    }

    fn read(&self, opts: &ReadOptions) -> Result<TetMesh, MeshError> {
        let p = self.parse()?;
        self.convert(p.msh, &p.names, p.fmt, opts)
    }

    /// The header, `$PhysicalNames` and mshio's parse of the whole file.
    fn parse(&self) -> Result<Parsed, MeshError> {
        let fmt = self.read_format()?;
        let names = self.read_physical_names()?;
        let bytes = self.bytes;
        // mshio has a few `unimplemented!`/`expect` paths and unchecked
        // arithmetic; turn any panic into an error.
        let parsed = std::panic::catch_unwind(|| {
            mshio::parse_msh_bytes(bytes).map_err(|e| describe_parse_error(bytes, &e))
        });
        let msh = match parsed {
            Ok(Ok(m)) => m,
            Ok(Err((offset, msg))) => return Err(self.malformed(offset, fmt.binary, msg)),
            Err(_) => {
                return Err(self.malformed(
                    None,
                    fmt.binary,
                    "the MSH parser (mshio) panicked on this file".into(),
                ))
            }
        };
        Ok(Parsed { msh, names, fmt })
    }

    /// Parses `$MeshFormat` ourselves: mshio's version error does not say
    /// which version the file has, and some header values make it panic.
    fn read_format(&self) -> Result<Format, MeshError> {
        let b = self.bytes;
        let start = b
            .iter()
            .position(|c| !c.is_ascii_whitespace())
            .unwrap_or(b.len());
        let (first, rest) = next_line(&b[start..]);
        if first.trim_ascii_end() != b"$MeshFormat" {
            return Err(self.malformed(
                Some(start),
                false,
                "expected `$MeshFormat` at the start of the file (is this a Gmsh .msh file?)"
                    .into(),
            ));
        }
        let line_off = b.len() - rest.len();
        let (line, after) = next_line(rest);
        let text = String::from_utf8_lossy(line);
        let tok: Vec<&str> = text.split_whitespace().collect();
        if tok.len() < 3 {
            return Err(self.malformed(
                Some(line_off),
                false,
                format!("expected `version file-type data-size` in $MeshFormat, found `{text}`"),
            ));
        }
        let version: f64 = tok[0].parse().map_err(|_| {
            self.malformed(
                Some(line_off),
                false,
                format!("invalid MSH version `{}`", tok[0]),
            )
        })?;
        if (version - 4.1).abs() > 1e-9 {
            return Err(MeshError::UnsupportedVersion {
                path: self.path.to_path_buf(),
                version: tok[0].to_string(),
            });
        }
        let binary = match tok[1] {
            "0" => false,
            "1" => true,
            t => {
                return Err(self.malformed(
                    Some(line_off),
                    false,
                    format!("invalid file type `{t}` in $MeshFormat (0 = ASCII, 1 = binary)"),
                ))
            }
        };
        let size_t: usize = match tok[2].parse() {
            Ok(s @ (4 | 8)) => s,
            _ if !binary => 8,
            _ => {
                return Err(self.malformed(
                    Some(line_off),
                    false,
                    format!("unsupported data size `{}` in $MeshFormat (4 or 8)", tok[2]),
                ))
            }
        };
        let mut big_endian = false;
        if binary {
            let off = b.len() - after.len();
            big_endian = match after.get(..4) {
                Some([1, 0, 0, 0]) => false,
                Some([0, 0, 0, 1]) => true,
                _ => {
                    return Err(self.malformed(
                        Some(off),
                        false,
                        "binary $MeshFormat must contain the integer 1 after the version line"
                            .into(),
                    ))
                }
            };
        }
        Ok(Format {
            binary,
            size_t,
            big_endian,
        })
    }

    /// Parses `$PhysicalNames` (ASCII in both ASCII and binary files).
    fn read_physical_names(&self) -> Result<HashMap<(i32, i32), String>, MeshError> {
        let mut names = HashMap::new();
        let Some(pos) = find_line(self.bytes, b"$PhysicalNames", 0) else {
            return Ok(names);
        };
        let (_, mut rest) = next_line(&self.bytes[pos..]);
        let off = |rest: &[u8]| self.bytes.len() - rest.len();
        let err = |o: usize, m: String| self.malformed(Some(o), false, m);
        let (line, r) = next_line(rest);
        let count: usize = String::from_utf8_lossy(line)
            .trim()
            .parse()
            .map_err(|_| err(off(rest), "expected the number of physical names".into()))?;
        rest = r;
        for _ in 0..count {
            let o = off(rest);
            let (line, r) = next_line(rest);
            let text = String::from_utf8_lossy(line);
            let mut it = text.trim_start().splitn(3, char::is_whitespace);
            let dim = it.next().and_then(|s| s.parse::<i32>().ok());
            let tag = it.next().and_then(|s| s.parse::<i32>().ok());
            let name = it.next().map(str::trim).and_then(|s| {
                s.strip_prefix('"')
                    .and_then(|s| s.strip_suffix('"'))
                    .map(str::to_string)
            });
            match (dim, tag, name) {
                (Some(d), Some(t), Some(n)) if r.len() < rest.len() => {
                    names.insert((d, t), n);
                }
                _ => {
                    return Err(err(
                        o,
                        format!("expected `dim tag \"name\"` in $PhysicalNames, found `{text}`"),
                    ))
                }
            }
            rest = r;
        }
        let (line, _) = next_line(rest);
        if line.trim_ascii() != b"$EndPhysicalNames" {
            return Err(err(
                off(rest),
                format!("expected `$EndPhysicalNames` after {count} physical names"),
            ));
        }
        Ok(names)
    }

    /// Node tags per `$Nodes` block, read directly from the file. Needed
    /// because mshio discards the tags when they are dense.
    fn scan_node_tags(&self, fmt: Format) -> Result<Vec<Vec<u64>>, MeshError> {
        let b = self.bytes;
        let pos = find_line(b, b"$Nodes", 0)
            .ok_or_else(|| self.malformed(None, fmt.binary, "no $Nodes section".into()))?;
        let (_, rest) = next_line(&b[pos..]);
        let mut cur = Cursor {
            b,
            pos: b.len() - rest.len(),
            fmt,
        };
        let trunc = |c: &Cursor| {
            self.malformed(
                Some(c.pos),
                fmt.binary,
                "truncated or malformed $Nodes section".into(),
            )
        };
        let num_blocks = cur.size_t().ok_or_else(|| trunc(&cur))?;
        for _ in 0..3 {
            cur.size_t().ok_or_else(|| trunc(&cur))?;
        }
        let mut out = Vec::new();
        for _ in 0..num_blocks {
            for _ in 0..3 {
                cur.int().ok_or_else(|| trunc(&cur))?;
            }
            let n = cur.size_t().ok_or_else(|| trunc(&cur))? as usize;
            let mut tags = Vec::with_capacity(n.min(b.len()));
            for _ in 0..n {
                tags.push(cur.size_t().ok_or_else(|| trunc(&cur))?);
            }
            cur.skip_doubles(3 * n).ok_or_else(|| trunc(&cur))?;
            out.push(tags);
        }
        Ok(out)
    }

    /// All nodes of `$Nodes` as (Gmsh tag, coordinates), sorted by tag;
    /// an error if a tag is defined twice.
    fn sorted_nodes(
        &self,
        msh: &MshFile<u64, i32, f64>,
        fmt: Format,
    ) -> Result<Vec<(u64, [f64; 3])>, MeshError> {
        let nodes_sec = msh
            .data
            .nodes
            .as_ref()
            .ok_or_else(|| self.invalid("the file has no $Nodes section".into()))?;
        let mut dense: Option<Vec<Vec<u64>>> = None;
        let mut all: Vec<(u64, [f64; 3])> = Vec::new();
        for (bi, block) in nodes_sec.node_blocks.iter().enumerate() {
            let tags: Vec<u64> = match &block.node_tags {
                Some(map) => {
                    if map.len() != block.nodes.len() {
                        return Err(self.invalid(format!(
                            "$Nodes block {} (entity dim {}, tag {}) contains a node tag twice",
                            bi + 1,
                            block.entity_dim,
                            block.entity_tag
                        )));
                    }
                    let mut t = vec![0u64; block.nodes.len()];
                    for (&tag, &i) in map {
                        t[i] = tag;
                    }
                    t
                }
                None => {
                    if dense.is_none() {
                        let scanned = self.scan_node_tags(fmt)?;
                        let consistent = scanned.len() == nodes_sec.node_blocks.len()
                            && scanned
                                .iter()
                                .zip(&nodes_sec.node_blocks)
                                .all(|(t, b)| t.len() == b.nodes.len());
                        if !consistent {
                            return Err(self.invalid(
                                "could not match the node tags of the $Nodes section with \
                                 mshio's parse (several $Nodes-like lines?)"
                                    .into(),
                            ));
                        }
                        dense = Some(scanned);
                    }
                    dense.as_ref().map(|d| d[bi].clone()).unwrap_or_default()
                }
            };
            all.extend(
                tags.into_iter()
                    .zip(block.nodes.iter().map(|n| [n.x, n.y, n.z])),
            );
        }
        all.sort_unstable_by_key(|n| n.0);
        if let Some(w) = all.windows(2).find(|w| w[0].0 == w[1].0) {
            return Err(self.invalid(format!("node tag {} is defined more than once", w[0].0)));
        }
        Ok(all)
    }

    /// Index (into the tag-sorted node list) of node `tag`, used by the
    /// element with Gmsh tag `elem_tag`.
    fn node_index(&self, index: &TagIndex, tag: u64, elem_tag: u64) -> Result<u32, MeshError> {
        index.get(tag).ok_or_else(|| {
            self.invalid(format!(
                "element with gmsh tag {elem_tag} refers to node tag {tag}, \
                 which is not defined in $Nodes"
            ))
        })
    }

    /// Keeps the nodes marked `used`, renumbered 0-based in tag order:
    /// (coordinates, Gmsh tags, new index per old index or `u32::MAX`).
    /// Errors on a non-finite coordinate of a kept node.
    fn compact_nodes(
        &self,
        all: &[(u64, [f64; 3])],
        used: &[bool],
    ) -> Result<CompactNodes, MeshError> {
        let mut new_id = vec![u32::MAX; all.len()];
        let mut nodes = Vec::new();
        let mut node_tags = Vec::new();
        for (i, id) in new_id.iter_mut().enumerate() {
            if used[i] {
                let (tag, x) = all[i];
                if !x.iter().all(|c| c.is_finite()) {
                    return Err(self.invalid(format!(
                        "node with gmsh tag {tag} has a non-finite coordinate ({}, {}, {})",
                        x[0], x[1], x[2]
                    )));
                }
                *id = u32::try_from(nodes.len())
                    .map_err(|_| MeshError::TooLarge(format!("more than {} nodes", u32::MAX)))?;
                nodes.push(x);
                node_tags.push(tag);
            }
        }
        Ok(CompactNodes {
            nodes,
            tags: node_tags,
            new_id,
        })
    }

    fn convert(
        &self,
        msh: MshFile<u64, i32, f64>,
        names: &HashMap<(i32, i32), String>,
        fmt: Format,
        opts: &ReadOptions,
    ) -> Result<TetMesh, MeshError> {
        let group_name = |dim: i32, tag: i32| group_name(names, dim, tag);
        let phys = physical_tags(&msh);
        let no_phys: Vec<i32> = Vec::new();
        let phys_of = |dim: i32, tag: i32| phys.get(&(dim, tag)).unwrap_or(&no_phys);
        let all = self.sorted_nodes(&msh, fmt)?;
        let index = TagIndex::new(&all);
        let lookup = |tag: u64, elem_tag: u64| self.node_index(&index, tag, elem_tag);

        // ---- Elements.
        struct RawTet {
            tag: u64,
            nodes: [u32; 4],
            entity: i32,
        }
        let mut raw_tets: Vec<RawTet> = Vec::new();
        let mut raw_tris: Vec<(u64, [u32; 3], i32)> = Vec::new();
        let mut raw_node_sets: BTreeMap<String, Vec<u32>> = BTreeMap::new();
        let empty_blocks = Vec::new();
        let blocks = msh
            .data
            .elements
            .as_ref()
            .map_or(&empty_blocks, |e| &e.element_blocks);
        let tet_count: usize = blocks
            .iter()
            .filter(|b| b.entity_dim == 3)
            .map(|b| b.elements.len())
            .sum();
        super::check_element_count(&format!("'{}'", self.path.display()), tet_count as u128)?;
        for block in blocks {
            let (dim, etag) = (block.entity_dim, block.entity_tag);
            let ptags = phys_of(dim, etag);
            match dim {
                3 => {
                    if block.element_type != ElementType::Tet4 {
                        if let Some(first) = block.elements.first() {
                            return Err(MeshError::UnsupportedElement {
                                path: self.path.to_path_buf(),
                                gmsh_tag: first.element_tag,
                                entity: etag,
                                type_code: block.element_type as i32,
                                type_name: format!("{:?}", block.element_type),
                                supported: "linear tetrahedra (Gmsh type 4)",
                            });
                        }
                        continue;
                    }
                    raw_tets.reserve(block.elements.len());
                    for el in &block.elements {
                        let mut nodes = [0u32; 4];
                        for (k, &t) in el.nodes.iter().enumerate().take(4) {
                            nodes[k] = lookup(t, el.element_tag)?;
                        }
                        raw_tets.push(RawTet {
                            tag: el.element_tag,
                            nodes,
                            entity: etag,
                        });
                    }
                }
                2 => {
                    if ptags.is_empty() || block.elements.is_empty() {
                        continue;
                    }
                    if block.element_type != ElementType::Tri3 {
                        return Err(self.invalid(format!(
                            "physical surface '{}' (surface entity {etag}) contains elements of \
                             Gmsh type {} ({:?}); only linear triangles (Gmsh type 2) are \
                             supported on physical surfaces",
                            group_name(2, ptags[0]),
                            block.element_type as i32,
                            block.element_type
                        )));
                    }
                    for el in &block.elements {
                        let mut nodes = [0u32; 3];
                        for (k, &t) in el.nodes.iter().enumerate().take(3) {
                            nodes[k] = lookup(t, el.element_tag)?;
                        }
                        raw_tris.push((el.element_tag, nodes, etag));
                    }
                }
                0 | 1 => {
                    for &p in ptags {
                        let set = raw_node_sets.entry(group_name(dim, p)).or_default();
                        for el in &block.elements {
                            for &t in &el.nodes {
                                set.push(lookup(t, el.element_tag)?);
                            }
                        }
                    }
                }
                _ => {
                    return Err(
                        self.invalid(format!("element block with invalid entity dimension {dim}"))
                    )
                }
            }
        }
        if raw_tets.is_empty() {
            return Err(self.invalid(
                "the file contains no linear tetrahedra (Gmsh type 4); \
                 was a 3D mesh generated and saved?"
                    .into(),
            ));
        }
        raw_tets.sort_by_key(|t| t.tag);
        if let Some(w) = raw_tets.windows(2).find(|w| w[0].tag == w[1].tag) {
            return Err(self.invalid(format!("element tag {} is used more than once", w[0].tag)));
        }

        // ---- Bodies from physical volumes.
        let vol_phys: BTreeSet<i32> = raw_tets
            .iter()
            .map(|t| t.entity)
            .collect::<BTreeSet<_>>()
            .into_iter()
            .flat_map(|e| phys_of(3, e).iter().copied())
            .collect();
        let body_of_phys: HashMap<i32, u32> = vol_phys
            .iter()
            .enumerate()
            .map(|(i, &p)| (p, i as u32))
            .collect();
        let mut body = Vec::with_capacity(raw_tets.len());
        let mut elem_sets: BTreeMap<String, Vec<u32>> = BTreeMap::new();
        if let Some(ent) = &msh.data.entities {
            for v in &ent.volumes {
                for &p in &v.physical_tags {
                    elem_sets.entry(group_name(3, p)).or_default();
                }
            }
        }
        let mut orphans = 0usize;
        let mut first_orphan = None;
        for (e, t) in raw_tets.iter().enumerate() {
            let ptags = phys_of(3, t.entity);
            let b = ptags.iter().filter_map(|p| body_of_phys.get(p)).min();
            match b {
                Some(&b) => body.push(b),
                None => {
                    if first_orphan.is_none() {
                        first_orphan = Some((t.tag, t.entity));
                    }
                    orphans += 1;
                    body.push(0);
                }
            }
            for &p in ptags {
                if let Some(s) = elem_sets.get_mut(&group_name(3, p)) {
                    s.push(e as u32);
                }
            }
        }
        if let (false, Some((tag, ent))) = (vol_phys.is_empty(), first_orphan) {
            return Err(self.invalid(format!(
                "{orphans} tetrahedra (first: gmsh tag {tag}, volume entity {ent}) belong to no \
                 physical volume, but the file defines physical volumes; add them to a physical \
                 volume or remove all physical volumes"
            )));
        }
        for s in elem_sets.values_mut() {
            s.sort_unstable();
            s.dedup();
        }

        // ---- Keep nodes used by tets or node sets; renumber in tag order.
        let mut used = vec![false; all.len()];
        for t in &raw_tets {
            for &v in &t.nodes {
                used[v as usize] = true;
            }
        }
        for s in raw_node_sets.values() {
            for &v in s {
                used[v as usize] = true;
            }
        }
        let CompactNodes {
            nodes,
            tags: node_tags,
            new_id,
        } = self.compact_nodes(&all, &used)?;
        let tets: Vec<[u32; 4]> = raw_tets
            .iter()
            .map(|t| t.nodes.map(|v| new_id[v as usize]))
            .collect();
        let tet_tags: Vec<u64> = raw_tets.iter().map(|t| t.tag).collect();
        let mut mesh = TetMesh {
            nodes,
            tets,
            body,
            node_sets: BTreeMap::new(),
            face_sets: BTreeMap::new(),
            elem_sets,
        };
        if opts.fix_orientation {
            mesh.fix_orientation();
        }
        mesh.validate_impl(Some((&tet_tags, &node_tags)))
            .map_err(|e| MeshError::InFile {
                path: self.path.to_path_buf(),
                source: Box::new(e),
            })?;

        // ---- Node sets (also empty ones for every physical point/curve).
        if let Some(ent) = &msh.data.entities {
            for p in ent.points.iter().flat_map(|p| &p.physical_tags) {
                mesh.node_sets.entry(group_name(0, *p)).or_default();
            }
            for p in ent.curves.iter().flat_map(|c| &c.physical_tags) {
                mesh.node_sets.entry(group_name(1, *p)).or_default();
            }
        }
        for (name, raw) in raw_node_sets {
            let s = mesh.node_sets.entry(name).or_default();
            s.extend(raw.iter().map(|&v| new_id[v as usize]));
            s.sort_unstable();
            s.dedup();
        }

        // ---- Face sets, oriented by their owning tet.
        if let Some(ent) = &msh.data.entities {
            for p in ent.surfaces.iter().flat_map(|s| &s.physical_tags) {
                mesh.face_sets.entry(group_name(2, *p)).or_default();
            }
        }
        if !raw_tris.is_empty() {
            raw_tris.sort_by_key(|t| t.0);
            let boundary: HashMap<[u32; 3], [u32; 3]> = mesh
                .boundary_faces()
                .into_iter()
                .map(|f| (sorted3(f.nodes), f.nodes))
                .collect();
            let mut seen: HashMap<String, HashSet<[u32; 3]>> = HashMap::new();
            for (tag, tri, entity) in &raw_tris {
                let ids = tri.map(|v| new_id[v as usize]);
                let key = sorted3(ids);
                for &p in phys_of(2, *entity) {
                    let name = group_name(2, p);
                    let Some(&oriented) = boundary.get(&key) else {
                        return Err(self.face_not_on_boundary(&mesh, *tag, tri, &all, ids, &name));
                    };
                    if seen.entry(name.clone()).or_default().insert(key) {
                        mesh.face_sets.entry(name).or_default().push(oriented);
                    }
                }
            }
        }
        Ok(mesh)
    }

    fn face_not_on_boundary(
        &self,
        mesh: &TetMesh,
        tag: u64,
        tri: &[u32; 3],
        all: &[(u64, [f64; 3])],
        ids: [u32; 3],
        name: &str,
    ) -> MeshError {
        let owners = if ids.contains(&u32::MAX) {
            0
        } else {
            mesh.tets
                .iter()
                .filter(|t| ids.iter().all(|v| t.contains(v)))
                .count()
        };
        let why = match owners {
            0 => "it is not a face of any tetrahedron".to_string(),
            n => format!("it is an interior face shared by {n} tetrahedra"),
        };
        let gtags = tri.map(|v| all[v as usize].0);
        self.invalid(format!(
            "triangle with gmsh tag {tag} (nodes {}, {}, {}) of physical surface '{name}' is not \
             a boundary face of the tetrahedral mesh: {why}",
            gtags[0], gtags[1], gtags[2]
        ))
    }
}

fn sorted3(mut a: [u32; 3]) -> [u32; 3] {
    a.sort_unstable();
    a
}

/// Gmsh node tag -> index into the tag-sorted node list.
enum TagIndex {
    Dense { min: u64, idx: Vec<u32> },
    Sparse(HashMap<u64, u32>),
}

impl TagIndex {
    fn new(sorted: &[(u64, [f64; 3])]) -> TagIndex {
        let (Some(first), Some(last)) = (sorted.first(), sorted.last()) else {
            return TagIndex::Sparse(HashMap::new());
        };
        let span = last.0 - first.0;
        if span <= 4 * sorted.len() as u64 + 1024 {
            let mut idx = vec![u32::MAX; span as usize + 1];
            for (i, n) in sorted.iter().enumerate() {
                idx[(n.0 - first.0) as usize] = i as u32;
            }
            TagIndex::Dense { min: first.0, idx }
        } else {
            TagIndex::Sparse(
                sorted
                    .iter()
                    .enumerate()
                    .map(|(i, n)| (n.0, i as u32))
                    .collect(),
            )
        }
    }

    fn get(&self, tag: u64) -> Option<u32> {
        match self {
            TagIndex::Dense { min, idx } => {
                let i = tag.checked_sub(*min)?;
                idx.get(usize::try_from(i).ok()?)
                    .copied()
                    .filter(|&v| v != u32::MAX)
            }
            TagIndex::Sparse(m) => m.get(&tag).copied(),
        }
    }
}

/// Reads numbers of the `$Nodes` section in ASCII or binary layout.
struct Cursor<'a> {
    b: &'a [u8],
    pos: usize,
    fmt: Format,
}

impl Cursor<'_> {
    fn token(&mut self) -> Option<&[u8]> {
        while self.b.get(self.pos)?.is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.b.len() && !self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some(&self.b[start..self.pos])
    }

    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let s = self.b.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(s)
    }

    fn uint(&mut self, n: usize) -> Option<u64> {
        let big = self.fmt.big_endian;
        let s = self.take(n)?;
        let mut v = 0u64;
        for k in 0..n {
            let byte = if big { s[k] } else { s[n - 1 - k] };
            v = (v << 8) | byte as u64;
        }
        Some(v)
    }

    fn size_t(&mut self) -> Option<u64> {
        if self.fmt.binary {
            self.uint(self.fmt.size_t)
        } else {
            std::str::from_utf8(self.token()?).ok()?.parse().ok()
        }
    }

    fn int(&mut self) -> Option<i64> {
        if self.fmt.binary {
            Some(self.uint(4)? as u32 as i32 as i64)
        } else {
            std::str::from_utf8(self.token()?).ok()?.parse().ok()
        }
    }

    fn skip_doubles(&mut self, n: usize) -> Option<()> {
        if self.fmt.binary {
            self.take(n.checked_mul(8)?)?;
        } else {
            for _ in 0..n {
                self.token()?;
            }
        }
        Some(())
    }
}

/// Turns mshio's error into (byte offset, message). mshio's own `Display`
/// hex-dumps the whole rest of the file, so it is not used.
fn describe_parse_error(bytes: &[u8], e: &mshio::MshParserError<&[u8]>) -> (Option<usize>, String) {
    let offset_of = |s: &[u8]| {
        let base = bytes.as_ptr() as usize;
        let p = s.as_ptr() as usize;
        (p >= base && p <= base + bytes.len()).then(|| p - base)
    };
    let filtered: Vec<_> = e
        .backtrace
        .iter()
        .filter(|(_, k)| !k.is_nom_error())
        .collect();
    let Some((input, _)) = filtered.first() else {
        let offset = e.backtrace.first().and_then(|(s, _)| offset_of(s));
        return (
            offset,
            "unexpected content or end of file (no further detail from mshio)".into(),
        );
    };
    // Outermost first: contexts form a path, other kinds say what failed.
    let mut path = Vec::new();
    let mut what = Vec::new();
    for (_, k) in filtered.iter().rev() {
        match k.context() {
            Some(c) => path.push(c.to_string()),
            None => what.push(k.to_string().trim_end_matches('.').to_string()),
        }
    }
    let mut msg = if what.is_empty() {
        "parse error".to_string()
    } else {
        what.join("; ")
    };
    if !path.is_empty() {
        let _ = write!(msg, " (in {})", path.join(" > "));
    }
    if input.is_empty() {
        msg.push_str(" (unexpected end of file)");
    }
    (offset_of(input), msg)
}

mod hex;
mod write;
pub use hex::read_msh_hex8;
pub use write::write_msh_ascii;

#[cfg(test)]
mod tests;
