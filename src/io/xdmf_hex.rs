//! The second index of a series with Hex8 bodies (issue 21),
//! `<stem>_hex8.xdmf`: the Hex8 bodies as one grid of `Hexahedron` cells,
//! over the same files as the main index. The hexes' corners are the mesh
//! file's `/mesh/hexes` (global node ids, seed 002 Table 1 order, which is
//! the XDMF/VTK hexahedron order: the bottom face counter-clockwise seen
//! from +z, then the top face above it), body after body. A body's hex `h`
//! is its tets `6 h .. 6 h + 6`, each carrying its hex's cell values; the
//! hexes' cell fields are stored once more per hex (`/static/hex/<name>`,
//! `/fields/hex/<name>`: the first tet's row), because ParaView's two XDMF
//! readers take different selections of every sixth row (the legacy one a
//! `HyperSlab` item, the Xdmf3 ones a `|start:stride:count:dims` suffix, each
//! ignoring the other's) and plain datasets read in both. It costs a sixth
//! of the Hex8 bodies' cell data.

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

impl XdmfModel {
    /// A field's data item in the hex grid: node fields as in the main
    /// index, cell fields from the hexes' own rows (`<file>:/<kind>/hex/<name>`).
    fn hex_rows(
        &self,
        center: Center,
        indent: &str,
        path: &str,
        width: usize,
        number: &str,
    ) -> String {
        let rows = match center {
            Center::Node => self.nodes,
            Center::Cell => self.hexes,
        };
        let dims = if width == 1 {
            rows.to_string()
        } else {
            format!("{rows} {width}")
        };
        format!(
            "{indent}<DataItem Dimensions=\"{dims}\" {number} Format=\"HDF\">{path}</DataItem>\n"
        )
    }

    /// The group of a field of `center` in the hex grid.
    fn hex_group(center: Center) -> &'static str {
        match center {
            Center::Node => Center::Node.group(),
            Center::Cell => "hex",
        }
    }

    /// Topology, geometry and static attributes of the hex grid.
    fn hex_grid_head(&self, indent: &str) -> String {
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
            let name = escape(name);
            let path = format!("{h5}:/static/{}/{name}", Self::hex_group(*center));
            let int = "NumberType=\"Int\" Precision=\"4\"";
            let _ = write!(
                s,
                "{indent}<Attribute Name=\"{name}\" AttributeType=\"Scalar\" Center=\"{c}\">\n{}{indent}</Attribute>\n",
                self.hex_rows(*center, &format!("{indent}  "), &path, 1, int),
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
        let head = |indent: &str| self.hex_grid_head(indent);
        Some(self.document("hex8", head, |k, steps, s| {
            for f in &self.fields {
                let name = escape(&f.name);
                let path = format!(
                    "{steps}/{}:/fields/{}/{name}",
                    step_file_name(k),
                    Self::hex_group(f.center)
                );
                let ty = attribute_type(f.components).unwrap_or("Matrix");
                let float = "NumberType=\"Float\" Precision=\"8\"";
                let _ = write!(
                    s,
                    "        <Attribute Name=\"{name}\" AttributeType=\"{ty}\" Center=\"{c}\">\n{}        </Attribute>\n",
                    self.hex_rows(f.center, "          ", &path, f.components, float),
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
    fn hex_index_reads_the_hexes_own_rows_of_the_cell_fields() {
        let s = model().render_hexes().unwrap();
        assert_eq!(s.matches("TopologyType=\"Hexahedron\"").count(), 2);
        assert!(s.contains("NumberOfElements=\"4\""));
        assert!(s.contains(
            "Dimensions=\"4 8\" NumberType=\"UInt\" Precision=\"4\" Format=\"HDF\">out.h5:/mesh/hexes<"
        ));
        assert!(
            !s.contains("HyperSlab")
                && !s.contains("/fields/cell/")
                && !s.contains("/static/cell/")
        );
        assert!(s.contains(
            "Dimensions=\"4 6\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">out_steps/000001.h5:/fields/hex/stress</DataItem>"
        ));
        assert!(s.contains(
            "Dimensions=\"4\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">out.h5:/static/hex/body</DataItem>"
        ));
        assert!(s.contains(
            "Dimensions=\"40 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">out_steps/000001.h5:/fields/node/displacement</DataItem>"
        ));
        // The XML is balanced.
        for tag in ["Grid", "DataItem", "Attribute", "Topology", "Geometry"] {
            let open = s.matches(&format!("<{tag} ")).count();
            assert_eq!(open, s.matches(&format!("</{tag}>")).count(), "{tag}");
        }
        // A Tet4 body between them changes nothing: the hexes' rows are their own.
        let mut gap = model();
        gap.hex_blocks[1].first_tet = 30;
        assert_eq!(gap.render_hexes().unwrap(), s);
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
        assert!(!m.contains("<Time ") && m.contains("/static/hex/body"));
        assert_eq!(
            hex_index_path(Path::new("d/run.xdmf")),
            Path::new("d/run_hex8.xdmf")
        );
    }
}
