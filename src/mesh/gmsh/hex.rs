//! Gmsh MSH 4.1 import of 8-node hexahedra ([`read_msh_hex8`]) for the
//! FE–DE kernels of seed 002 (issue 21), sharing the parsing and the errors
//! of the Tet4 reader of the parent module.

use std::collections::BTreeMap;
use std::path::Path;

use mshio::ElementType;
use nalgebra::Vector3;

use super::{group_name, physical_tags, read_bytes, CompactNodes, Reader, TagIndex};
use crate::mechanics::hex8::{hex8_jacobian, hex8_size, HEX8_NATURAL};
use crate::mesh::hex8::HexMesh;
use crate::mesh::{MeshError, DEGENERATE_REL_TOL};

/// `TABLE1_FROM_GMSH[k]` is the Gmsh local node that is node k of seed 002
/// Table 1 ([`HEX8_NATURAL`]). Gmsh's 8-node hexahedron (type 5), as drawn
/// in the Gmsh reference manual ("Node ordering"), has nodes 0-1-2-3 on the
/// face w = −1 counter-clockwise about +w, from (−1, −1, −1), then 4-5-6-7
/// on the face w = +1 above them: Table 1's order. The map is therefore the
/// identity; it is kept explicit (and checked against both coordinate
/// tables by a unit test) so that a change on either side shows.
const TABLE1_FROM_GMSH: [usize; 8] = [0, 1, 2, 3, 4, 5, 6, 7];

/// Reads the 8-node hexahedra of a Gmsh MSH 4.1 file (ASCII or binary) into
/// a [`HexMesh`]. Errors name the file, and where possible the line or byte
/// offset, the Gmsh element tag or the element type.
///
/// * Hexahedra (Gmsh type 5) become elements, ordered by ascending Gmsh
///   element tag, their nodes mapped from Gmsh's local order to that of
///   seed 002 Table 1 (`TABLE1_FROM_GMSH`).
/// * Elements of dimension 0–2 (points, lines, triangles, quadrangles) are
///   not elements of the mesh; the nodes of those in physical groups become
///   node sets named as by [`read_msh`](super::read_msh).
/// * Any other 3D element (tetrahedra, prisms, pyramids, quadratic
///   hexahedra) is [`MeshError::UnsupportedElement`] naming its type.
/// * Nodes used by hexahedra or node sets are kept and renumbered 0-based
///   in ascending Gmsh node tag.
/// * Every hexahedron's Jacobian determinant (seed 002 eq 9) is checked at
///   the centre and at the eight corners: negative is an inverted element,
///   at most [`DEGENERATE_REL_TOL`] × (longest edge)³ / 8 a degenerate one,
///   both errors naming the Gmsh element tag and node tags. (The scale is
///   that of the Tet4 check: the volume 8 det J of a parallelepiped against
///   `DEGENERATE_REL_TOL` × edge³.)
pub fn read_msh_hex8(path: &Path) -> Result<HexMesh, MeshError> {
    let bytes = read_bytes(path)?;
    let reader = Reader {
        path,
        bytes: &bytes,
    };
    let p = reader.parse()?;
    let phys = physical_tags(&p.msh);
    let all = reader.sorted_nodes(&p.msh, p.fmt)?;
    let index = TagIndex::new(&all);
    let lookup = |tag: u64, elem_tag: u64| reader.node_index(&index, tag, elem_tag);

    let blocks = p
        .msh
        .data
        .elements
        .as_ref()
        .map_or(&[][..], |e| &e.element_blocks[..]);
    let count: usize = blocks
        .iter()
        .filter(|b| b.entity_dim == 3)
        .map(|b| b.elements.len())
        .sum();
    crate::mesh::check_element_count(&format!("'{}'", path.display()), count as u128)?;
    // (Gmsh tag, nodes as indices into `all`, Table 1 order).
    let mut raw: Vec<(u64, [u32; 8])> = Vec::with_capacity(count);
    let mut raw_sets: BTreeMap<String, Vec<u32>> = BTreeMap::new();
    for block in blocks {
        let (dim, entity) = (block.entity_dim, block.entity_tag);
        match dim {
            3 if block.element_type == ElementType::Hex8 => {
                for el in &block.elements {
                    let mut nodes = [0u32; 8];
                    for (k, &g) in TABLE1_FROM_GMSH.iter().enumerate() {
                        nodes[k] = lookup(el.nodes[g], el.element_tag)?;
                    }
                    raw.push((el.element_tag, nodes));
                }
            }
            3 => {
                if let Some(first) = block.elements.first() {
                    return Err(MeshError::UnsupportedElement {
                        path: path.to_path_buf(),
                        gmsh_tag: first.element_tag,
                        entity,
                        type_code: block.element_type as i32,
                        type_name: format!("{:?}", block.element_type),
                        supported: "8-node hexahedra (Gmsh type 5)",
                    });
                }
            }
            0..=2 => {
                for &ptag in phys.get(&(dim, entity)).into_iter().flatten() {
                    let set = raw_sets.entry(group_name(&p.names, dim, ptag)).or_default();
                    for el in &block.elements {
                        for &t in &el.nodes {
                            set.push(lookup(t, el.element_tag)?);
                        }
                    }
                }
            }
            _ => {
                return Err(
                    reader.invalid(format!("element block with invalid entity dimension {dim}"))
                )
            }
        }
    }
    if raw.is_empty() {
        return Err(reader.invalid(
            "the file contains no 8-node hexahedra (Gmsh type 5); was a 3D hexahedral mesh \
             (recombined, or transfinite with Recombine) generated and saved?"
                .into(),
        ));
    }
    raw.sort_by_key(|h| h.0);
    if let Some(w) = raw.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(reader.invalid(format!("element tag {} is used more than once", w[0].0)));
    }

    let mut used = vec![false; all.len()];
    for &v in raw
        .iter()
        .flat_map(|h| h.1.iter())
        .chain(raw_sets.values().flatten())
    {
        used[v as usize] = true;
    }
    let CompactNodes { nodes, new_id, .. } = reader.compact_nodes(&all, &used)?;
    let mut hexes = Vec::with_capacity(raw.len());
    for (tag, h) in &raw {
        let ids = h.map(|v| new_id[v as usize]);
        check_jacobian(&reader, *tag, &h.map(|v| all[v as usize].0), &ids, &nodes)?;
        hexes.push(ids);
    }
    let mut node_sets = BTreeMap::new();
    for (name, raw) in raw_sets {
        let mut s: Vec<u32> = raw.iter().map(|&v| new_id[v as usize]).collect();
        s.sort_unstable();
        s.dedup();
        node_sets.insert(name, s);
    }
    Ok(HexMesh {
        nodes,
        hexes,
        node_sets,
    })
}

/// An error naming the Gmsh element `tag` (and its Gmsh node tags, in
/// Table 1 order) unless
/// det J (seed 002 eq 9) is positive and above the degenerate tolerance at
/// the centre and at every corner.
fn check_jacobian(
    reader: &Reader,
    tag: u64,
    gmsh_nodes: &[u64; 8],
    ids: &[u32; 8],
    nodes: &[[f64; 3]],
) -> Result<(), MeshError> {
    let x = ids.map(|v| Vector3::from(nodes[v as usize]));
    let tol = DEGENERATE_REL_TOL * hex8_size(&x).powi(3) / 8.0;
    let points = std::iter::once((Vector3::zeros(), "the centre".to_string())).chain(
        HEX8_NATURAL
            .iter()
            .zip(gmsh_nodes)
            .map(|(xi, t)| (Vector3::from(*xi), format!("the corner at node tag {t}"))),
    );
    for (xi, at) in points {
        let det = hex8_jacobian(&x, &xi).determinant();
        if det > tol {
            continue;
        }
        let what = if det < 0.0 { "inverted" } else { "degenerate" };
        let list = gmsh_nodes.map(|t| t.to_string()).join(",");
        return Err(reader.invalid(format!(
            "hexahedron with gmsh tag {tag} (gmsh node tags {list}) is {what}: Jacobian \
             determinant {det:.3e} at {at} (degenerate below {tol:.3e}); Gmsh's node order is \
             the face w = -1 counter-clockwise seen from +w, then the face above it"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
