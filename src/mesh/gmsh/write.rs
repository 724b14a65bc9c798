//! Gmsh MSH 4.1 ASCII export: one volume entity and physical volume per
//! body, one surface entity and physical surface per face set.

use std::collections::{BTreeSet, HashMap};
use std::io::Write as _;
use std::path::Path;

use super::super::{MeshError, TetMesh};

/// Writes `mesh` as a Gmsh MSH 4.1 ASCII file.
///
/// * Node `i` gets tag `i + 1`, element `e` tag `e + 1`; nodes are grouped
///   in one block per volume entity (the body of the first element using
///   them).
/// * One volume entity and physical volume per distinct body id (ascending,
///   entity/physical tags 1, 2, ...). The physical volume is named after an
///   element set that contains exactly the body's elements if there is one,
///   otherwise `body_<id>`.
/// * One surface entity and physical surface per face set (triangles
///   written as given; face sets must consist of boundary faces to be
///   readable by [`read_msh`](super::read_msh)).
///
/// Round trip through [`read_msh`](super::read_msh) reproduces nodes (if all are used by
/// elements), elements and their order, face sets (up to the rotation of
/// each triangle's nodes), and bodies if the body ids are `0..k`
/// (otherwise they are compacted to `0..k` in ascending order). Node sets
/// and element sets that are not a body's element set are not written.
///
/// Errors: a mesh without elements, inconsistent indices, non-finite
/// coordinates, set names containing `"` or line breaks, I/O errors.
pub fn write_msh_ascii(mesh: &TetMesh, path: &Path) -> Result<(), MeshError> {
    let invalid = |message: String| MeshError::InvalidGmsh {
        path: path.to_path_buf(),
        message,
    };
    if mesh.tets.is_empty() {
        return Err(invalid("cannot write a mesh without elements".into()));
    }
    if mesh.body.len() != mesh.tets.len() {
        return Err(MeshError::BodyLength {
            body_len: mesh.body.len(),
            num_elems: mesh.tets.len(),
        });
    }
    let n = mesh.nodes.len();
    if let Some((i, p)) = mesh
        .nodes
        .iter()
        .enumerate()
        .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
    {
        return Err(MeshError::NonFiniteNode {
            node: i as u32,
            coords: *p,
        });
    }
    mesh.check_node_indices()?;
    for (name, faces) in &mesh.face_sets {
        if let Some(&bad) = faces.iter().flatten().find(|&&v| v as usize >= n) {
            return Err(MeshError::SetOutOfRange {
                kind: "face",
                name: name.clone(),
                item: "node",
                index: bad,
                count: n,
            });
        }
    }
    let check_name = |name: &str| {
        if name.contains(['"', '\n', '\r']) {
            Err(invalid(format!(
                "set name {name:?} cannot be written to a Gmsh file (contains a quote or line break)"
            )))
        } else {
            Ok(())
        }
    };

    // Bodies -> volume entities 1..=k.
    let bodies: Vec<u32> = mesh
        .body
        .iter()
        .copied()
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    let rank: HashMap<u32, usize> = bodies.iter().enumerate().map(|(i, &b)| (b, i)).collect();
    let mut vol_elems: Vec<Vec<u32>> = vec![Vec::new(); bodies.len()];
    for (e, b) in mesh.body.iter().enumerate() {
        vol_elems[rank[b]].push(e as u32);
    }
    let mut vol_names = Vec::with_capacity(bodies.len());
    for (i, elems) in vol_elems.iter().enumerate() {
        let name = mesh
            .elem_sets
            .iter()
            .find(|(_, s)| *s == elems)
            .map(|(name, _)| name.clone())
            .unwrap_or_else(|| format!("body_{}", bodies[i]));
        check_name(&name)?;
        vol_names.push(name);
    }
    for name in mesh.face_sets.keys() {
        check_name(name)?;
    }

    // Nodes -> volume entity of the first element using them.
    let mut node_vol = vec![usize::MAX; n];
    for (t, b) in mesh.tets.iter().zip(&mesh.body) {
        for &v in t {
            if node_vol[v as usize] == usize::MAX {
                node_vol[v as usize] = rank[b];
            }
        }
    }
    let mut vol_nodes: Vec<Vec<usize>> = vec![Vec::new(); bodies.len()];
    for (v, r) in node_vol.iter().enumerate() {
        vol_nodes[if *r == usize::MAX { 0 } else { *r }].push(v);
    }

    let write_err = |source| MeshError::Write {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(write_err)?;
    let mut out = std::io::BufWriter::new(file);
    let layout = Layout {
        vol_names: &vol_names,
        vol_elems: &vol_elems,
        vol_nodes: &vol_nodes,
    };
    write_ascii(mesh, &layout, &mut out)
        .and_then(|()| out.flush())
        .map_err(write_err)
}

/// What [`write_msh_ascii`] decided to write: per volume entity its
/// physical name, elements and nodes.
struct Layout<'a> {
    vol_names: &'a [String],
    vol_elems: &'a [Vec<u32>],
    vol_nodes: &'a [Vec<usize>],
}

fn write_ascii(mesh: &TetMesh, l: &Layout, w: &mut impl std::io::Write) -> std::io::Result<()> {
    let bbox = |pts: &mut dyn Iterator<Item = usize>| {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in pts {
            for d in 0..3 {
                lo[d] = lo[d].min(mesh.nodes[v][d]);
                hi[d] = hi[d].max(mesh.nodes[v][d]);
            }
        }
        if lo[0] > hi[0] {
            ([0.0; 3], [0.0; 3])
        } else {
            (lo, hi)
        }
    };
    let nv = l.vol_names.len();
    let n = mesh.nodes.len();

    writeln!(w, "$MeshFormat\n4.1 0 8\n$EndMeshFormat")?;
    writeln!(w, "$PhysicalNames\n{}", nv + mesh.face_sets.len())?;
    for (j, name) in mesh.face_sets.keys().enumerate() {
        writeln!(w, "2 {} \"{name}\"", j + 1)?;
    }
    for (i, name) in l.vol_names.iter().enumerate() {
        writeln!(w, "3 {} \"{name}\"", i + 1)?;
    }
    writeln!(w, "$EndPhysicalNames")?;

    // Entities: `tag minX minY minZ maxX maxY maxZ 1 physicalTag 0` (no bounding entities).
    writeln!(w, "$Entities\n0 0 {} {nv}", mesh.face_sets.len())?;
    for (j, faces) in mesh.face_sets.values().enumerate() {
        let (lo, hi) = bbox(&mut faces.iter().flatten().map(|&v| v as usize));
        writeln!(
            w,
            "{} {:?} {:?} {:?} {:?} {:?} {:?} 1 {} 0",
            j + 1,
            lo[0],
            lo[1],
            lo[2],
            hi[0],
            hi[1],
            hi[2],
            j + 1
        )?;
    }
    for (i, nodes) in l.vol_nodes.iter().enumerate() {
        let (lo, hi) = bbox(&mut nodes.iter().copied());
        writeln!(
            w,
            "{} {:?} {:?} {:?} {:?} {:?} {:?} 1 {} 0",
            i + 1,
            lo[0],
            lo[1],
            lo[2],
            hi[0],
            hi[1],
            hi[2],
            i + 1
        )?;
    }
    writeln!(w, "$EndEntities")?;

    writeln!(w, "$Nodes\n{nv} {n} 1 {n}")?;
    for (i, nodes) in l.vol_nodes.iter().enumerate() {
        writeln!(w, "3 {} 0 {}", i + 1, nodes.len())?;
        for &v in nodes {
            writeln!(w, "{}", v + 1)?;
        }
        for &v in nodes {
            let p = mesh.nodes[v];
            // `{:?}` prints the shortest representation that round-trips exactly.
            writeln!(w, "{:?} {:?} {:?}", p[0], p[1], p[2])?;
        }
    }
    writeln!(w, "$EndNodes")?;

    let num_tris: usize = mesh.face_sets.values().map(Vec::len).sum();
    let total = mesh.tets.len() + num_tris;
    let face_blocks = mesh.face_sets.values().filter(|f| !f.is_empty()).count();
    writeln!(w, "$Elements\n{} {total} 1 {total}", nv + face_blocks)?;
    for (i, elems) in l.vol_elems.iter().enumerate() {
        writeln!(w, "3 {} 4 {}", i + 1, elems.len())?;
        for &e in elems {
            let t = mesh.tets[e as usize];
            writeln!(
                w,
                "{} {} {} {} {}",
                e + 1,
                t[0] + 1,
                t[1] + 1,
                t[2] + 1,
                t[3] + 1
            )?;
        }
    }
    let mut tag = mesh.tets.len();
    for (j, faces) in mesh.face_sets.values().enumerate() {
        if faces.is_empty() {
            continue;
        }
        writeln!(w, "2 {} 2 {}", j + 1, faces.len())?;
        for f in faces {
            tag += 1;
            writeln!(w, "{tag} {} {} {}", f[0] + 1, f[1] + 1, f[2] + 1)?;
        }
    }
    writeln!(w, "$EndElements")?;
    Ok(())
}
