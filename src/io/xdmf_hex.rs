//! The second index of a series with Hex8 bodies (issue 21),
//! `<stem>_hex8.xdmf`: the Hex8 bodies as one grid of `Hexahedron` cells,
//! over the same files as the main index. The hexes' corners are the mesh
//! file's `/mesh/hexes` (global node ids, seed 002 Table 1 order, which is
//! the XDMF/VTK hexahedron order: the bottom face counter-clockwise seen
//! from +z, then the top face above it), body after body. A body's hex `h`
//! is its tets `6 h .. 6 h + 6`, each carrying its hex's cell values, so
//! when the Hex8 bodies' tets follow one another a cell field of the hexes
//! is the tets' dataset read with a stride of 6 (an XDMF `HyperSlab`, which
//! ParaView's legacy XDMF reader reads; its Xdmf3 readers skip it): nothing
//! is written twice. With a Tet4 body between Hex8 bodies the index has the
//! node fields only.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::xdmf::{attribute_type, escape, step_file_name, Center, XdmfModel};

/// The hexes of one Hex8 body in the series.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct HexBlock {
    /// The body's name (the grid's name).
    pub body: String,
    /// Global element id (row of `/mesh/topology`) of its first tet.
    pub first_tet: u64,
    /// Row of `/mesh/hexes` of its first hex.
    pub first_hex: u64,
    /// Its number of hexes.
    pub count: u64,
}

/// `<dir>/<stem>_hex8.xdmf` for the main index `<dir>/<stem>.xdmf`.
pub fn hex_index_path(xdmf: &Path) -> PathBuf {
    let stem = xdmf.file_stem().unwrap_or_default().to_string_lossy();
    xdmf.with_file_name(format!("{stem}_hex8.xdmf"))
}

/// How the hyperslab's start, stride and count are given.
const SEL: &str = "NumberType=\"UInt\" Precision=\"8\" Format=\"XML\"";

/// An HDF5 dataset read with a hyperslab: rows `start, start + stride, …`
/// (`count` of them) of a `[rows, width]` dataset (`width` 1: a vector).
fn slab(
    indent: &str,
    path: &str,
    (rows, width): (u64, usize),
    (start, stride, count): (u64, u64, u64),
    number: &str,
) -> String {
    let (dims, sel, full) = if width == 1 {
        (
            count.to_string(),
            format!("3 1\" {SEL}>{start} {stride} {count}"),
            rows.to_string(),
        )
    } else {
        (
            format!("{count} {width}"),
            format!("3 2\" {SEL}>{start} 0 {stride} 1 {count} {width}"),
            format!("{rows} {width}"),
        )
    };
    format!(
        "{indent}<DataItem ItemType=\"HyperSlab\" Dimensions=\"{dims}\" {number} Type=\"HyperSlab\">\n\
         {indent}  <DataItem Dimensions=\"{sel}</DataItem>\n\
         {indent}  <DataItem Dimensions=\"{full}\" {number} Format=\"HDF\">{path}</DataItem>\n\
         {indent}</DataItem>\n"
    )
}

impl XdmfModel {
    /// The row of the tets' cell datasets that holds the first hex's
    /// values, when every hex's first tet is six rows after the previous
    /// hex's: the Hex8 bodies' tets follow one another with no Tet4 body
    /// between them. Otherwise the hex index has no cell fields.
    fn hex_cell_start(&self) -> Option<u64> {
        let first = self.hex_blocks.first()?.first_tet;
        let mut next = first;
        for b in &self.hex_blocks {
            if b.first_tet != next {
                return None;
            }
            next += 6 * b.count;
        }
        Some(first)
    }

    /// A field's data item in the hex grid: node fields whole, cell fields
    /// every sixth row from `start`.
    fn hex_rows(
        &self,
        center: Center,
        start: u64,
        indent: &str,
        path: &str,
        width: usize,
        number: &str,
    ) -> String {
        match center {
            Center::Node => {
                let dims = if width == 1 {
                    self.nodes.to_string()
                } else {
                    format!("{} {width}", self.nodes)
                };
                format!("{indent}<DataItem Dimensions=\"{dims}\" {number} Format=\"HDF\">{path}</DataItem>\n")
            }
            Center::Cell => slab(
                indent,
                path,
                (self.cells, width),
                (start, 6, self.hexes),
                number,
            ),
        }
    }

    /// Topology, geometry and static attributes of the hex grid.
    fn hex_grid_head(&self, cell_start: Option<u64>, indent: &str) -> String {
        let h5 = escape(&self.h5_name);
        let (n, nh) = (self.nodes, self.hexes);
        let mut s = format!(
            "{indent}<Topology TopologyType=\"Hexahedron\" NumberOfElements=\"{nh}\" NodesPerElement=\"8\">\n\
             {indent}  <DataItem Dimensions=\"{nh} 8\" NumberType=\"UInt\" Precision=\"4\" Format=\"HDF\">{h5}:/mesh/hexes</DataItem>\n\
             {indent}</Topology>\n\
             {indent}<Geometry GeometryType=\"XYZ\">\n\
             {indent}  <DataItem Dimensions=\"{n} 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{h5}:/mesh/coordinates</DataItem>\n\
             {indent}</Geometry>\n",
        );
        for (name, center) in &self.statics {
            let start = match (center, cell_start) {
                (Center::Cell, None) => continue,
                (_, start) => start.unwrap_or(0),
            };
            let name = escape(name);
            let path = format!("{h5}:/static/{}/{name}", center.group());
            let int = "NumberType=\"Int\" Precision=\"4\"";
            let _ = write!(
                s,
                "{indent}<Attribute Name=\"{name}\" AttributeType=\"Scalar\" Center=\"{c}\">\n{}{indent}</Attribute>\n",
                self.hex_rows(*center, start, &format!("{indent}  "), &path, 1, int),
                c = center.xdmf(),
            );
        }
        s
    }

    /// The Hex8 index, `None` when the series has no Hex8 body: one grid of
    /// all the hexes (`/mesh/hexes` in the order of the bodies).
    pub(crate) fn render_hexes(&self) -> Option<String> {
        if self.hex_blocks.is_empty() {
            return None;
        }
        let cell_start = self.hex_cell_start();
        let head = |indent: &str| self.hex_grid_head(cell_start, indent);
        Some(self.document("hex8", head, |k, steps, s| {
            for f in &self.fields {
                let start = match (f.center, cell_start) {
                    (Center::Cell, None) => continue,
                    (_, start) => start.unwrap_or(0),
                };
                let name = escape(&f.name);
                let path = format!(
                    "{steps}/{}:/fields/{}/{name}",
                    step_file_name(k),
                    f.center.group()
                );
                let ty = attribute_type(f.components).unwrap_or("Matrix");
                let float = "NumberType=\"Float\" Precision=\"8\"";
                let _ = write!(
                    s,
                    "        <Attribute Name=\"{name}\" AttributeType=\"{ty}\" Center=\"{c}\">\n{}        </Attribute>\n",
                    self.hex_rows(f.center, start, "          ", &path, f.components, float),
                    c = f.center.xdmf(),
                );
            }
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::xdmf::FieldDesc;

    fn model() -> XdmfModel {
        XdmfModel {
            h5_name: "out.h5".into(),
            steps_name: "out_steps".into(),
            nodes: 40,
            cells: 30,
            nodes_per_cell: 4,
            statics: vec![("body".into(), Center::Cell)],
            fields: vec![
                FieldDesc {
                    name: "displacement".into(),
                    center: Center::Node,
                    components: 3,
                },
                FieldDesc {
                    name: "stress".into(),
                    center: Center::Cell,
                    components: 6,
                },
            ],
            times: vec![0.0, 1e-3],
            hexes: 4,
            hex_blocks: vec![
                HexBlock {
                    body: "a".into(),
                    first_tet: 6,
                    first_hex: 0,
                    count: 3,
                },
                HexBlock {
                    body: "b".into(),
                    first_tet: 24,
                    first_hex: 3,
                    count: 1,
                },
            ],
        }
    }

    #[test]
    fn hex_index_reads_the_tets_cell_rows_with_a_stride_of_six() {
        let s = model().render_hexes().unwrap();
        assert_eq!(s.matches("TopologyType=\"Hexahedron\"").count(), 2);
        assert!(s.contains("NumberOfElements=\"4\""));
        assert!(s.contains(
            "Dimensions=\"4 8\" NumberType=\"UInt\" Precision=\"4\" Format=\"HDF\">out.h5:/mesh/hexes<"
        ));
        // Blocks a and b follow one another: rows 6, 12, 18 and 24 of 30.
        assert!(s.contains(&format!("Dimensions=\"3 2\" {SEL}>6 0 6 1 4 6</DataItem>")));
        assert!(s.contains(&format!("Dimensions=\"3 1\" {SEL}>6 6 4</DataItem>")));
        assert!(s.contains("Dimensions=\"30 6\" NumberType=\"Float\""));
        assert!(s.contains(">out_steps/000001.h5:/fields/cell/stress</DataItem>"));
        assert!(s.contains(">out_steps/000001.h5:/fields/node/displacement</DataItem>"));
        // The XML is balanced.
        for tag in ["Grid", "DataItem", "Attribute", "Topology", "Geometry"] {
            let open = s.matches(&format!("<{tag} ")).count();
            assert_eq!(open, s.matches(&format!("</{tag}>")).count(), "{tag}");
        }
        // A Tet4 body between them: no stride reaches both, no cell fields.
        let mut gap = model();
        gap.hex_blocks[1].first_tet = 30;
        let g = gap.render_hexes().unwrap();
        assert!(!g.contains("Center=\"Cell\"") && g.contains("/fields/node/displacement"));
        let none = XdmfModel {
            hex_blocks: Vec::new(),
            ..model()
        };
        assert!(none.render_hexes().is_none());
        let mesh_only = XdmfModel {
            times: Vec::new(),
            ..model()
        };
        let m = mesh_only.render_hexes().unwrap();
        assert!(!m.contains("<Time ") && m.contains("/static/cell/body"));
        assert_eq!(
            hex_index_path(Path::new("d/run.xdmf")),
            Path::new("d/run_hex8.xdmf")
        );
    }
}
