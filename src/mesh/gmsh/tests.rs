//! Tests of the Gmsh reader/writer on small hand-written ASCII files and
//! binary files generated here following the MSH 4.1 specification.

use super::*;
use crate::mesh::generate::box_mesh;
use std::path::PathBuf;

/// Unit cube, 6 tets (Kuhn split), node tags 10..80 (sparse), physical
/// surfaces `left` (x=0, one triangle written inward) and `right` (x=1,
/// one triangle inward), physical volume `solid`, physical point `corner`.
const CUBE_ASCII: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
4
0 5 "corner"
2 1 "left"
2 2 "right"
3 3 "solid"
$EndPhysicalNames
$Entities
1 0 2 1
1 1 1 1 1 5
1 0 0 0 0 1 1 1 1 0
2 1 0 0 1 1 1 1 2 0
1 0 0 0 1 1 1 1 3 0
$EndEntities
$Nodes
2 8 10 80
3 1 0 5
10
30
50
70
20
0 0 0
0 1 0
0 0 1
0 1 1
1 0 0
3 1 0 3
40
60
80
1 1 0
1 0 1
1 1 1
$EndNodes
$Elements
4 11 1 11
0 1 15 1
11 80
2 1 2 2
7 10 30 70
8 10 50 70
2 2 2 2
9 20 40 80
10 20 60 80
3 1 4 6
1 10 20 40 80
2 10 20 80 60
3 10 30 80 40
4 10 30 70 80
5 10 50 60 80
6 10 50 80 70
$EndElements
"#;

/// Node `i` of the cube (0-based, tag order) is at these coordinates.
fn cube_node(i: usize) -> [f64; 3] {
    [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64]
}
const CUBE_TETS: [[u32; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 7, 5],
    [0, 2, 7, 3],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 7, 6],
];
/// Triangles as written in the files (some inward).
const LEFT: [[u32; 3]; 2] = [[0, 2, 6], [0, 4, 6]];
const RIGHT: [[u32; 3]; 2] = [[1, 3, 7], [1, 5, 7]];

fn write_tmp(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn sorted_faces(faces: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut v: Vec<_> = faces.iter().map(|f| sorted3(*f)).collect();
    v.sort_unstable();
    v
}

fn check_cube(m: &TetMesh) {
    assert_eq!(m.nodes, (0..8).map(cube_node).collect::<Vec<_>>());
    assert_eq!(m.tets, CUBE_TETS.to_vec());
    assert_eq!(m.body, vec![0; 6]);
    assert_eq!(m.elem_sets.len(), 1);
    assert_eq!(m.elem_sets["solid"], (0..6).collect::<Vec<u32>>());
    assert_eq!(m.node_sets.len(), 1);
    assert_eq!(m.node_sets["corner"], vec![7]);
    assert_eq!(m.face_sets.len(), 2);
    for (name, tris, nx) in [("left", LEFT, -1.0), ("right", RIGHT, 1.0)] {
        let f = &m.face_sets[name];
        assert_eq!(sorted_faces(f), sorted_faces(&tris), "{name}");
        for tri in f {
            let (a, n) = m.face_area_normal(*tri);
            assert!((a - 0.5).abs() < 1e-15);
            assert_eq!(n, [nx, 0.0, 0.0], "{name} must point outward");
        }
    }
    assert_eq!(m.set_nodes("left"), Some(vec![0, 2, 4, 6]));
    assert!((m.total_volume() - 1.0).abs() < 1e-14);
}

/// Writes MSH numbers in ASCII (space separated) or binary layout.
struct MshWriter {
    binary: bool,
    big_endian: bool,
    buf: Vec<u8>,
}

impl MshWriter {
    fn text(&mut self, s: &str) {
        self.buf.extend_from_slice(s.as_bytes());
    }
    /// Line break in ASCII mode only (binary data has no separators).
    fn eol(&mut self) {
        if !self.binary {
            self.buf.push(b'\n');
        }
    }
    fn raw(&mut self, le: &[u8]) {
        if self.big_endian {
            self.buf.extend(le.iter().rev());
        } else {
            self.buf.extend_from_slice(le);
        }
    }
    fn size_t(&mut self, v: u64) {
        if self.binary {
            self.raw(&v.to_le_bytes());
        } else {
            self.text(&format!("{v} "));
        }
    }
    fn int(&mut self, v: i32) {
        if self.binary {
            self.raw(&v.to_le_bytes());
        } else {
            self.text(&format!("{v} "));
        }
    }
    fn double(&mut self, v: f64) {
        if self.binary {
            self.raw(&v.to_le_bytes());
        } else {
            self.text(&format!("{v:?} "));
        }
    }
    /// Entity with bounding box, one physical tag and no bounding entities.
    fn entity(&mut self, tag: i32, lo: [f64; 3], hi: [f64; 3], phys: i32) {
        self.int(tag);
        for v in lo.iter().chain(&hi) {
            self.double(*v);
        }
        self.size_t(1);
        self.int(phys);
        self.size_t(0);
        self.eol();
    }
}

/// The cube of [`CUBE_ASCII`] in ASCII or binary MSH 4.1 layout, with node
/// tags `tag(i)` for node `i`; the 8 nodes are split into two blocks (nodes
/// 4..8 first, then 0..4).
fn cube_msh(binary: bool, big_endian: bool, tag: impl Fn(u32) -> u64) -> Vec<u8> {
    let mut w = MshWriter {
        binary,
        big_endian,
        buf: Vec::new(),
    };
    w.text(&format!("$MeshFormat\n4.1 {} 8\n", binary as i32));
    if binary {
        w.int(1);
        w.text("\n");
    }
    w.text("$EndMeshFormat\n");
    w.text("$PhysicalNames\n4\n0 5 \"corner\"\n2 1 \"left\"\n2 2 \"right\"\n3 3 \"solid\"\n");
    w.text("$EndPhysicalNames\n$Entities\n");
    for n in [1, 0, 2, 1] {
        w.size_t(n);
    }
    w.eol();
    // Point entity 1: tag x y z numPhysicalTags physicalTags.
    w.int(1);
    for _ in 0..3 {
        w.double(1.0);
    }
    w.size_t(1);
    w.int(5);
    w.eol();
    w.entity(1, [0.0; 3], [0.0, 1.0, 1.0], 1);
    w.entity(2, [1.0, 0.0, 0.0], [1.0; 3], 2);
    w.entity(1, [0.0; 3], [1.0; 3], 3);
    w.text("\n$EndEntities\n$Nodes\n");
    let tags: Vec<u64> = (0..8).map(&tag).collect();
    w.size_t(2);
    w.size_t(8);
    w.size_t(*tags.iter().min().unwrap());
    w.size_t(*tags.iter().max().unwrap());
    w.eol();
    for block in [4..8u32, 0..4] {
        w.int(3);
        w.int(1);
        w.int(0);
        w.size_t(4);
        w.eol();
        for i in block.clone() {
            w.size_t(tag(i));
            w.eol();
        }
        for i in block {
            for c in cube_node(i as usize) {
                w.double(c);
            }
            w.eol();
        }
    }
    w.text("\n$EndNodes\n$Elements\n");
    for n in [4, 11, 1, 11] {
        w.size_t(n);
    }
    w.eol();
    let block = |w: &mut MshWriter, dim: i32, etag: i32, ty: i32, elems: &[(u64, Vec<u32>)]| {
        w.int(dim);
        w.int(etag);
        w.int(ty);
        w.size_t(elems.len() as u64);
        w.eol();
        for (t, nodes) in elems {
            w.size_t(*t);
            for &n in nodes {
                w.size_t(tag(n));
            }
            w.eol();
        }
    };
    block(&mut w, 0, 1, 15, &[(11, vec![7])]);
    block(
        &mut w,
        2,
        1,
        2,
        &[(7, LEFT[0].to_vec()), (8, LEFT[1].to_vec())],
    );
    block(
        &mut w,
        2,
        2,
        2,
        &[(9, RIGHT[0].to_vec()), (10, RIGHT[1].to_vec())],
    );
    let tets: Vec<_> = (0..6)
        .map(|e| (e as u64 + 1, CUBE_TETS[e].to_vec()))
        .collect();
    block(&mut w, 3, 1, 4, &tets);
    w.text("\n$EndElements\n");
    w.buf
}

#[test]
fn ascii_cube() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_tmp(&dir, "cube.msh", CUBE_ASCII.as_bytes());
    let m = read_msh(&p).unwrap();
    check_cube(&m);
    m.validate().unwrap();

    let crlf = CUBE_ASCII.replace('\n', "\r\n");
    let p = write_tmp(&dir, "cube_crlf.msh", crlf.as_bytes());
    assert_eq!(read_msh(&p).unwrap(), m);
}

#[test]
fn generated_ascii_matches_literal() {
    let dir = tempfile::tempdir().unwrap();
    let reference = read_msh(&write_tmp(&dir, "a.msh", CUBE_ASCII.as_bytes())).unwrap();
    // Same tags as the literal file.
    let bytes = cube_msh(false, false, |i| 10 * (i as u64 + 1));
    assert_eq!(
        read_msh(&write_tmp(&dir, "b.msh", &bytes)).unwrap(),
        reference
    );
    // Dense tags 1..8, but the first block holds tags 5..8: mshio drops
    // dense tags, so this exercises the $Nodes tag scanner.
    let bytes = cube_msh(false, false, |i| i as u64 + 1);
    assert_eq!(
        read_msh(&write_tmp(&dir, "c.msh", &bytes)).unwrap(),
        reference
    );
}

#[test]
fn binary_equals_ascii() {
    let dir = tempfile::tempdir().unwrap();
    let reference = read_msh(&write_tmp(&dir, "a.msh", CUBE_ASCII.as_bytes())).unwrap();
    for (big_endian, dense) in [(false, true), (false, false), (true, true), (true, false)] {
        let bytes = cube_msh(true, big_endian, |i| {
            if dense {
                i as u64 + 1
            } else {
                1000 + 7 * i as u64
            }
        });
        let p = write_tmp(&dir, "bin.msh", &bytes);
        let m = read_msh(&p).unwrap_or_else(|e| panic!("be={big_endian} dense={dense}: {e}"));
        assert_eq!(m, reference, "be={big_endian} dense={dense}");
    }
}

#[test]
fn missing_file_names_path() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("does_not_exist.msh");
    let e = read_msh(&p).unwrap_err();
    assert!(matches!(e, MeshError::Read { .. }));
    let msg = e.to_string();
    assert!(msg.contains("does_not_exist.msh"), "{msg}");
}

#[test]
fn inverted_tet_names_gmsh_tag() {
    let dir = tempfile::tempdir().unwrap();
    let text = CUBE_ASCII.replace("4 10 30 70 80", "4 10 30 80 70");
    let p = write_tmp(&dir, "inv.msh", text.as_bytes());
    let e = read_msh(&p).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("inv.msh"), "{msg}");
    assert!(msg.contains("element 3 (gmsh tag 4) is inverted"), "{msg}");
    // The nodes are named by the file's tags, not by 0-based indices.
    assert!(msg.contains("gmsh node tags 10,30,80,70"), "{msg}");
    let MeshError::InFile { source, .. } = e else {
        panic!("expected InFile, got {e:?}")
    };
    assert!(matches!(
        *source,
        MeshError::Inverted {
            elem: 3,
            gmsh_tag: Some(4),
            ..
        }
    ));
    let fixed = read_msh_with(
        &p,
        &ReadOptions {
            fix_orientation: true,
        },
    )
    .unwrap();
    check_cube(&fixed);
}

#[test]
fn degenerate_tet_names_gmsh_tag() {
    let dir = tempfile::tempdir().unwrap();
    let text = CUBE_ASCII.replace("4 10 30 70 80", "4 10 30 70 70");
    let p = write_tmp(&dir, "deg.msh", text.as_bytes());
    let msg = read_msh(&p).unwrap_err().to_string();
    assert!(msg.contains("(gmsh tag 4) is degenerate"), "{msg}");
}

#[test]
fn truncated_file_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let full = CUBE_ASCII.as_bytes();
    let binary = cube_msh(true, false, |i| i as u64 + 1);
    for (name, bytes) in [("t.msh", full), ("tb.msh", &binary[..])] {
        // Every prefix that cuts into the file before `$EndElements`.
        let end = bytes.len() - "$EndElements\n".len();
        for len in 0..end {
            let p = write_tmp(&dir, name, &bytes[..len]);
            let msg = match read_msh(&p) {
                Ok(_) => panic!("prefix of length {len} of {name} was accepted"),
                Err(e) => e.to_string(),
            };
            assert!(msg.contains(name), "{msg}");
            assert!(!msg.contains("panicked"), "len {len}: {msg}");
        }
    }
}

#[test]
fn malformed_content_reports_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = CUBE_ASCII.replace("0 1 1\n1 0 0", "0 1 x\n1 0 0");
    let p = write_tmp(&dir, "bad.msh", text.as_bytes());
    let e = read_msh(&p).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, MeshError::MalformedGmsh { .. }), "{msg}");
    assert!(msg.contains("bad.msh"), "{msg}");
    assert!(msg.contains("line 29"), "{msg}");
    assert!(msg.contains("$Nodes"), "{msg}");

    let p = write_tmp(&dir, "junk.msh", b"hello world\n");
    let msg = read_msh(&p).unwrap_err().to_string();
    assert!(
        msg.contains("junk.msh") && msg.contains("$MeshFormat"),
        "{msg}"
    );
}

#[test]
fn old_version_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n";
    let p = write_tmp(&dir, "old.msh", text.as_bytes());
    let e = read_msh(&p).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, MeshError::UnsupportedVersion { .. }));
    assert!(
        msg.contains("old.msh") && msg.contains("2.2") && msg.contains("4.1"),
        "{msg}"
    );
}

#[test]
fn higher_order_tets_are_rejected() {
    let dir = tempfile::tempdir().unwrap();
    // Declare the tet block as Tet10 with 10 (reused) node tags per element.
    let mut text = CUBE_ASCII.replace("3 1 4 6", "3 1 11 1");
    let start = text.find("1 10 20 40 80").unwrap();
    let end = text.find("$EndElements").unwrap();
    text.replace_range(start..end, "1 10 20 40 80 30 50 60 70 10 20\n");
    let text = text.replace("4 11 1 11", "4 6 1 11");
    let p = write_tmp(&dir, "p2.msh", text.as_bytes());
    let e = read_msh(&p).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("only linear tetrahedra (Gmsh type 4) are supported"),
        "{msg}"
    );
    assert!(
        msg.contains("type 11 (Tet10)") && msg.contains("p2.msh"),
        "{msg}"
    );
}

#[test]
fn interior_triangle_in_physical_surface_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    // (10, 20, 80) = nodes 0,1,7 is shared by tets 1 and 2.
    let text = CUBE_ASCII.replace("7 10 30 70", "7 10 20 80");
    let p = write_tmp(&dir, "int.msh", text.as_bytes());
    let msg = read_msh(&p).unwrap_err().to_string();
    assert!(msg.contains("int.msh") && msg.contains("'left'"), "{msg}");
    assert!(
        msg.contains("interior face shared by 2 tetrahedra"),
        "{msg}"
    );
    assert!(msg.contains("gmsh tag 7"), "{msg}");
}

#[test]
fn unknown_node_tag_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let text = CUBE_ASCII.replace("5 10 50 60 80", "5 10 50 60 99");
    let p = write_tmp(&dir, "unk.msh", text.as_bytes());
    let msg = read_msh(&p).unwrap_err().to_string();
    assert!(
        msg.contains("gmsh tag 5") && msg.contains("node tag 99"),
        "{msg}"
    );
}

#[test]
fn unnamed_groups_and_multiple_volumes() {
    let dir = tempfile::tempdir().unwrap();
    // No $PhysicalNames; tets 4..6 moved to a second volume entity with
    // physical tag 2 (lower than `solid`'s 3, so it becomes body 0).
    let start = CUBE_ASCII.find("$PhysicalNames").unwrap();
    let end = CUBE_ASCII.find("$Entities").unwrap();
    let mut text = CUBE_ASCII.to_string();
    text.replace_range(start..end, "");
    let text = text
        .replace("1 0 2 1\n", "1 0 2 2\n")
        .replace(
            "1 0 0 0 1 1 1 1 3 0\n",
            "1 0 0 0 1 1 1 1 3 0\n2 0 0 0 1 1 1 1 2 0\n",
        )
        .replace("4 11 1 11", "5 11 1 11")
        .replace(
            "3 1 4 6\n1 10 20 40 80\n2 10 20 80 60\n3 10 30 80 40\n",
            "3 1 4 3\n1 10 20 40 80\n2 10 20 80 60\n3 10 30 80 40\n3 2 4 3\n",
        );
    let p = write_tmp(&dir, "two.msh", text.as_bytes());
    let m = read_msh(&p).unwrap();
    assert_eq!(m.body, vec![1, 1, 1, 0, 0, 0]);
    assert_eq!(m.elem_sets["physical_3_3"], vec![0, 1, 2]);
    assert_eq!(m.elem_sets["physical_3_2"], vec![3, 4, 5]);
    assert_eq!(m.node_sets["physical_0_5"], vec![7]);
    assert_eq!(m.face_sets["physical_2_1"].len(), 2);
    assert_eq!(m.face_sets["physical_2_2"].len(), 2);

    // Tets outside every physical volume while physical volumes exist.
    let text = text.replace("2 0 0 0 1 1 1 1 2 0\n", "2 0 0 0 1 1 1 0 0\n");
    let p = write_tmp(&dir, "orphan.msh", text.as_bytes());
    let msg = read_msh(&p).unwrap_err().to_string();
    assert!(
        msg.contains("3 tetrahedra (first: gmsh tag 4, volume entity 2)"),
        "{msg}"
    );
}

#[test]
fn no_physical_volumes_gives_body_zero() {
    let dir = tempfile::tempdir().unwrap();
    let text = CUBE_ASCII.replace("1 0 0 0 1 1 1 1 3 0", "1 0 0 0 1 1 1 0 0");
    let p = write_tmp(&dir, "nophys.msh", text.as_bytes());
    let m = read_msh(&p).unwrap();
    assert_eq!(m.body, vec![0; 6]);
    assert!(m.elem_sets.is_empty());
    assert_eq!(m.face_sets["left"].len(), 2);
}

fn assert_same_face_sets(a: &TetMesh, b: &TetMesh) {
    assert_eq!(
        a.face_sets.keys().collect::<Vec<_>>(),
        b.face_sets.keys().collect::<Vec<_>>()
    );
    for (name, fa) in &a.face_sets {
        let fb = &b.face_sets[name];
        assert_eq!(sorted_faces(fa), sorted_faces(fb), "{name}");
        // Same orientation: b's triangle is a rotation of a's.
        let oriented: HashSet<[u32; 3]> = fa
            .iter()
            .flat_map(|f| [*f, [f[1], f[2], f[0]], [f[2], f[0], f[1]]])
            .collect();
        assert!(fb.iter().all(|f| oriented.contains(f)), "{name}");
    }
}

#[test]
fn write_read_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let mut m = box_mesh([0.0; 3], [1.0, 0.5, 0.5], 0.25).unwrap();
    let b = box_mesh([2.0, 0.1, -0.3], [0.5, 0.3, 0.1], 0.1).unwrap();
    m.append(b, 1);
    m.face_sets.insert("empty".into(), Vec::new());
    m.validate().unwrap();
    let p = dir.path().join("rt.msh");
    write_msh_ascii(&m, &p).unwrap();
    let r = read_msh(&p).unwrap();
    assert_eq!(r.nodes, m.nodes);
    assert_eq!(r.tets, m.tets);
    assert_eq!(r.body, m.body);
    assert_same_face_sets(&m, &r);
    assert!(r.face_sets["empty"].is_empty());
    let n0 = m.body.iter().filter(|&&b| b == 0).count() as u32;
    assert_eq!(r.elem_sets["body_0"], (0..n0).collect::<Vec<_>>());
    assert_eq!(
        r.elem_sets["body_1"],
        (n0..m.num_elems() as u32).collect::<Vec<_>>()
    );

    // A single body named by its element set; written again, identical file.
    let single = box_mesh([0.0; 3], [0.3, 0.2, 0.1], 0.1).unwrap();
    write_msh_ascii(&single, &p).unwrap();
    let r = read_msh(&p).unwrap();
    assert_eq!(r.elem_sets["all"], single.elem_sets["all"]);
    assert_eq!(
        (&r.nodes, &r.tets, &r.body),
        (&single.nodes, &single.tets, &single.body)
    );
    assert_same_face_sets(&single, &r);
    let first = std::fs::read(&p).unwrap();
    write_msh_ascii(&r, &p).unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), first);

    // The literal cube survives a round trip exactly (node sets aside).
    let cube = read_msh(&write_tmp(&dir, "c.msh", CUBE_ASCII.as_bytes())).unwrap();
    write_msh_ascii(&cube, &p).unwrap();
    let mut r = read_msh(&p).unwrap();
    r.node_sets = cube.node_sets.clone();
    assert_eq!(r, cube);
}

#[test]
fn write_rejects_bad_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("w.msh");
    let e = write_msh_ascii(&TetMesh::default(), &p).unwrap_err();
    assert!(e.to_string().contains("without elements"), "{e}");
    let mut m = box_mesh([0.0; 3], [1.0; 3], 1.0).unwrap();
    m.face_sets.insert("bad\"name".into(), Vec::new());
    assert!(write_msh_ascii(&m, &p).is_err());
    let mut m = box_mesh([0.0; 3], [1.0; 3], 1.0).unwrap();
    m.nodes[0][0] = f64::NAN;
    assert!(matches!(
        write_msh_ascii(&m, &p).unwrap_err(),
        MeshError::NonFiniteNode { node: 0, .. }
    ));
    let m = box_mesh([0.0; 3], [1.0; 3], 1.0).unwrap();
    let e = write_msh_ascii(&m, &dir.path().join("no_dir/x.msh")).unwrap_err();
    assert!(matches!(e, MeshError::Write { .. }) && e.to_string().contains("no_dir"));
}
