//! Tests of the Hex8 reader on small hand-written ASCII MSH 4.1 files.

use std::path::PathBuf;

use super::*;

/// Natural coordinates (u, v, w) of the nodes of Gmsh's 8-node hexahedron
/// (type 5) in Gmsh's local order, as drawn in the Gmsh reference manual
/// ("Node ordering"): 0-1-2-3 the face w = −1 counter-clockwise about +w,
/// then 4-5-6-7 the face w = +1 above them.
const GMSH_HEX8_NATURAL: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// Natural coordinates of Gmsh's node order map onto those of Table 1.
#[test]
fn gmsh_order_maps_onto_table1() {
    for (k, &g) in TABLE1_FROM_GMSH.iter().enumerate() {
        assert_eq!(HEX8_NATURAL[k], GMSH_HEX8_NATURAL[g], "Table 1 node {k}");
    }
}

/// Header, names and entities: surface 1 in physical surface `left`,
/// volume 1 in physical volume `solid`.
const HEAD: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
2 1 "left"
3 2 "solid"
$EndPhysicalNames
$Entities
0 0 1 1
1 0 0 0 0 0.5 0.25 1 1 0
1 0 0 0 2 0.5 0.25 1 2 0
$EndEntities
"#;

/// The box [0, 2] × [0, 0.5] × [0, 0.25] as 2 × 1 × 1 hexahedra: node
/// (i, j, k) has tag 1 + i + 3 j + 6 k and coordinates (i, j/2, k/4).
fn nodes() -> String {
    let mut s = String::from("$Nodes\n1 12 1 12\n3 1 0 12\n");
    for t in 1..=12 {
        s += &format!("{t}\n");
    }
    for k in 0..2 {
        for j in 0..2 {
            for i in 0..3 {
                s += &format!("{} {} {}\n", i as f64, j as f64 * 0.5, k as f64 * 0.25);
            }
        }
    }
    s + "$EndNodes\n"
}

/// The file with hexahedron tag 2 given by `hex2`, the face x = 0 as a
/// quadrangle (tag 1, physical `left`) and the extra volume block `extra`.
fn file(hex2: &str, extra: &str) -> String {
    let extra_blocks = usize::from(!extra.is_empty());
    let (blocks, count) = (2 + extra_blocks, 3 + extra_blocks);
    let mut s = format!("{HEAD}{}$Elements\n{blocks} {count} 1 {count}\n", nodes());
    s += "2 1 3 1\n1 1 4 10 7\n";
    // Tag 3 first: elements are ordered by tag.
    s += &format!("3 1 5 2\n3 2 3 6 5 8 9 12 11\n2 {hex2}\n");
    s += extra;
    s + "$EndElements\n"
}

const HEX2: &str = "1 2 5 4 7 8 11 10";

fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn volume(m: &HexMesh, e: usize) -> f64 {
    let x = m.element_coords(e).map(Vector3::from);
    8.0 * hex8_jacobian(&x, &Vector3::zeros()).determinant()
}

#[test]
fn two_hex_box_reads_back() {
    let dir = tempfile::tempdir().unwrap();
    let m = read_msh_hex8(&write(&dir, "box.msh", &file(HEX2, ""))).unwrap();
    assert_eq!(m.nodes.len(), 12);
    for (t, x) in m.nodes.iter().enumerate() {
        let (i, j, k) = (t % 3, (t / 3) % 2, t / 6);
        assert_eq!(
            *x,
            [i as f64, j as f64 * 0.5, k as f64 * 0.25],
            "node tag {}",
            t + 1
        );
    }
    assert_eq!(
        m.hexes,
        vec![[0, 1, 4, 3, 6, 7, 10, 9], [1, 2, 5, 4, 7, 8, 11, 10]]
    );
    for e in 0..2 {
        assert!((volume(&m, e) - 0.125).abs() < 1e-15, "element {e}");
    }
    assert_eq!(m.node_sets.len(), 1);
    assert_eq!(m.node_sets["left"], vec![0, 3, 6, 9]);
}

#[test]
fn inverted_hex_is_an_error_naming_its_tag() {
    let dir = tempfile::tempdir().unwrap();
    // Top face first: det J < 0 everywhere.
    let p = write(&dir, "inv.msh", &file("7 8 11 10 1 2 5 4", ""));
    let msg = read_msh_hex8(&p).unwrap_err().to_string();
    assert!(msg.contains("hexahedron with gmsh tag 2"), "{msg}");
    assert!(
        msg.contains("is inverted") && msg.contains("inv.msh"),
        "{msg}"
    );
    // A bottom face folded across itself: positive at the centre, negative
    // at corners.
    let p = write(&dir, "twist.msh", &file("1 2 4 5 7 8 11 10", ""));
    let msg = read_msh_hex8(&p).unwrap_err().to_string();
    assert!(
        msg.contains("gmsh tag 2") && msg.contains("the corner"),
        "{msg}"
    );
    // Top face collapsed onto the bottom one: det J = 0.
    let p = write(&dir, "flat.msh", &file("1 2 5 4 1 2 5 4", ""));
    let msg = read_msh_hex8(&p).unwrap_err().to_string();
    assert!(
        msg.contains("gmsh tag 2") && msg.contains("degenerate"),
        "{msg}"
    );
}

#[test]
fn other_3d_types_are_an_error_naming_the_type() {
    let dir = tempfile::tempdir().unwrap();
    let prism = "3 1 6 1\n4 1 2 4 7 8 10\n";
    let p = write(&dir, "prism.msh", &file(HEX2, prism));
    let err = read_msh_hex8(&p).unwrap_err();
    assert!(
        matches!(
            err,
            MeshError::UnsupportedElement {
                gmsh_tag: 4,
                type_code: 6,
                ..
            }
        ),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("(Pri6)") && msg.contains("only 8-node hexahedra"),
        "{msg}"
    );
    let tet10 = "3 1 11 1\n4 1 2 4 7 1 2 4 7 1 2\n";
    let msg = read_msh_hex8(&write(&dir, "tet10.msh", &file(HEX2, tet10)))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("type 11 (Tet10)"), "{msg}");
}

#[test]
fn a_file_without_hexahedra_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "{HEAD}{}$Elements\n1 1 1 1\n2 1 3 1\n1 1 4 10 7\n$EndElements\n",
        nodes()
    );
    let msg = read_msh_hex8(&write(&dir, "quads.msh", &text))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("no 8-node hexahedra"), "{msg}");
}
