//! XDMF index of a time series, rewritten atomically after every completed step.
//! The mesh and static fields come from the mesh file, each step's fields from
//! that step's own file; both are referred to by names relative to the index.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use super::xdmf_hex::HexBlock;
use super::IoError;

/// Where a field lives in the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Center {
    Node,
    Cell,
}

impl Center {
    pub(super) fn xdmf(self) -> &'static str {
        match self {
            Self::Node => "Node",
            Self::Cell => "Cell",
        }
    }

    /// HDF5 group holding this center's fields below `/static` or `/fields`.
    pub(crate) fn group(self) -> &'static str {
        match self {
            Self::Node => "node",
            Self::Cell => "cell",
        }
    }
}

/// XDMF attribute type for a component count, `None` if unsupported.
pub(crate) fn attribute_type(components: usize) -> Option<&'static str> {
    match components {
        1 => Some("Scalar"),
        3 => Some("Vector"),
        6 => Some("Tensor6"),
        9 => Some("Tensor"),
        _ => None,
    }
}

/// A time-dependent field as listed in the XDMF file.
#[derive(Clone, Debug)]
pub(crate) struct FieldDesc {
    pub name: String,
    pub center: Center,
    pub components: usize,
}

/// Everything needed to render the XDMF file.
#[derive(Clone, Debug, Default)]
pub(crate) struct XdmfModel {
    /// File name (no directory) of the mesh file, relative to the XDMF file.
    pub h5_name: String,
    /// Name of the directory of the step files, relative to the XDMF file.
    pub steps_name: String,
    pub nodes: u64,
    pub cells: u64,
    /// 4 (Tet4) or 3 (triangles).
    pub nodes_per_cell: usize,
    /// Static i32 fields: `(name, center)`, in [`XdmfModel::sort`] order.
    pub statics: Vec<(String, Center)>,
    /// Time-dependent fields, identical in every step, in
    /// [`XdmfModel::sort`] order.
    pub fields: Vec<FieldDesc>,
    /// Times of the completed steps.
    pub times: Vec<f64>,
    /// Rows of `/mesh/hexes` (0: no Hex8 body).
    pub hexes: u64,
    /// The Hex8 bodies, for the second index (`super::xdmf_hex`).
    pub hex_blocks: Vec<HexBlock>,
}

pub(super) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

impl XdmfModel {
    /// Puts the static and time-dependent fields in one order, node fields
    /// first, then by name, so that a series continued after a restart
    /// (which finds its fields in the files) is indexed like the original.
    pub(crate) fn sort(&mut self) {
        let key = |c: Center| c != Center::Node;
        self.statics
            .sort_by(|a, b| (key(a.1), &a.0).cmp(&(key(b.1), &b.0)));
        self.fields
            .sort_by(|a, b| (key(a.center), &a.name).cmp(&(key(b.center), &b.name)));
    }

    /// Topology, geometry and static attributes: identical for every step.
    fn mesh_block(&self, indent: &str) -> String {
        let h5 = escape(&self.h5_name);
        let (n, e, npc) = (self.nodes, self.cells, self.nodes_per_cell);
        let kind = match npc {
            1 => "Polyvertex",
            3 => "Triangle",
            _ => "Tetrahedron",
        };
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{indent}<Topology TopologyType=\"{kind}\" NumberOfElements=\"{e}\" NodesPerElement=\"{npc}\">\n\
             {indent}  <DataItem Dimensions=\"{e} {npc}\" NumberType=\"UInt\" Precision=\"4\" Format=\"HDF\">{h5}:/mesh/topology</DataItem>\n\
             {indent}</Topology>\n\
             {indent}<Geometry GeometryType=\"XYZ\">\n\
             {indent}  <DataItem Dimensions=\"{n} 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{h5}:/mesh/coordinates</DataItem>\n\
             {indent}</Geometry>"
        );
        for (name, center) in &self.statics {
            let rows = match center {
                Center::Node => n,
                Center::Cell => e,
            };
            let name = escape(name);
            let _ = writeln!(
                s,
                "{indent}<Attribute Name=\"{name}\" AttributeType=\"Scalar\" Center=\"{c}\">\n\
                 {indent}  <DataItem Dimensions=\"{rows}\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">{h5}:/static/{g}/{name}</DataItem>\n\
                 {indent}</Attribute>",
                c = center.xdmf(),
                g = center.group(),
            );
        }
        s
    }

    /// The XDMF document of the series: the grid `mesh_name` with its
    /// `head` (topology, geometry, static fields; given the indent) while no
    /// step is written, else a temporal collection of one grid per step:
    /// the head and what `step(k, steps_dir, out)` adds (its attributes).
    pub(super) fn document(
        &self,
        mesh_name: &str,
        head: impl Fn(&str) -> String,
        step: impl Fn(usize, &str, &mut String),
    ) -> String {
        let mut s = String::from(
            "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n\
             <!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n\
             <Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n\
             \x20 <Domain>\n",
        );
        if self.times.is_empty() {
            let _ = writeln!(s, "    <Grid Name=\"{mesh_name}\" GridType=\"Uniform\">");
            s.push_str(&head("      "));
            s.push_str("    </Grid>\n");
        } else {
            let mesh = head("        ");
            let steps = escape(&self.steps_name);
            s.push_str(
                "    <Grid Name=\"TimeSeries\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
            );
            for (k, t) in self.times.iter().enumerate() {
                let _ = writeln!(
                    s,
                    "      <Grid Name=\"step_{k:06}\" GridType=\"Uniform\">\n        <Time Value=\"{t:e}\"/>"
                );
                s.push_str(&mesh);
                step(k, &steps, &mut s);
                s.push_str("      </Grid>\n");
            }
            s.push_str("    </Grid>\n");
        }
        s.push_str("  </Domain>\n</Xdmf>\n");
        s
    }

    /// Renders the whole XDMF document (no step yet: the mesh and its
    /// static fields only).
    pub(crate) fn render(&self) -> String {
        self.document("mesh", |indent| self.mesh_block(indent), |k, steps, s| {
            for f in &self.fields {
                let rows = match f.center {
                    Center::Node => self.nodes,
                    Center::Cell => self.cells,
                };
                let c = f.components;
                let dims = if c == 1 {
                    rows.to_string()
                } else {
                    format!("{rows} {c}")
                };
                let ty = attribute_type(c).unwrap_or("Matrix");
                let name = escape(&f.name);
                let _ = writeln!(
                    s,
                    "        <Attribute Name=\"{name}\" AttributeType=\"{ty}\" Center=\"{center}\">\n\
                     \x20         <DataItem Dimensions=\"{dims}\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">{steps}/{file}:/fields/{g}/{name}</DataItem>\n\
                     \x20       </Attribute>",
                    center = f.center.xdmf(),
                    g = f.center.group(),
                    file = step_file_name(k),
                );
            }
        })
    }
}

/// Name of the file holding step `k`, inside the steps directory: `000012.h5`.
pub(crate) fn step_file_name(k: usize) -> String {
    format!("{k:06}.h5")
}

/// The step number of a step file's name (`000012.h5` is 12), `None` for
/// any other name (a `.part` file among them).
pub(crate) fn step_of_file_name(name: &str) -> Option<usize> {
    let digits = name.strip_suffix(".h5")?;
    if digits.len() < 6 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// `<path>.tmp`: the temporary file renamed over the XDMF file.
pub(crate) fn tmp_path(xdmf: &Path) -> PathBuf {
    let mut name = xdmf.as_os_str().to_owned();
    name.push(".tmp");
    PathBuf::from(name)
}

/// Replaces `path` by `text` atomically: writes and syncs `<path>.tmp`, then renames
/// it over `path`, so readers (and a crash) see either the old or the new file.
pub(crate) fn write_atomic(path: &Path, text: &str) -> Result<(), IoError> {
    let tmp = tmp_path(path);
    let mut file = std::fs::File::create(&tmp)
        .map_err(|e| IoError::io(&tmp, "creating temporary XDMF file", e))?;
    file.write_all(text.as_bytes())
        .map_err(|e| IoError::io(&tmp, "writing temporary XDMF file", e))?;
    file.sync_all()
        .map_err(|e| IoError::io(&tmp, "syncing temporary XDMF file", e))?;
    drop(file);
    std::fs::rename(&tmp, path).map_err(|e| IoError::io(path, "renaming XDMF file into place", e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_steps() {
        let m = XdmfModel {
            h5_name: "out.h5".into(),
            steps_name: "out_steps".into(),
            nodes: 5,
            cells: 2,
            nodes_per_cell: 4,
            statics: vec![("body".into(), Center::Node)],
            fields: vec![FieldDesc {
                name: "u".into(),
                center: Center::Node,
                components: 3,
            }],
            times: vec![0.0, 0.5],
            ..XdmfModel::default()
        };
        let s = m.render();
        assert_eq!(s.matches("<Grid Name=\"step_").count(), 2);
        assert!(s.contains(">out_steps/000001.h5:/fields/node/u</DataItem>"));
        assert!(s.contains(">out.h5:/mesh/coordinates</DataItem>"));
        assert!(s.contains("Dimensions=\"5 3\""));
        assert!(s.contains("out.h5:/static/node/body"));
        assert!(s.contains("<Time Value=\"5e-1\"/>"));
        assert!(s.contains("TopologyType=\"Tetrahedron\"") && s.contains("Dimensions=\"2 4\""));
        let tri = XdmfModel {
            nodes_per_cell: 3,
            ..m
        }
        .render();
        assert!(tri.contains("TopologyType=\"Triangle\"") && tri.contains("Dimensions=\"2 3\""));
    }

    #[test]
    fn step_file_names_round_trip() {
        assert_eq!(step_file_name(12), "000012.h5");
        assert_eq!(step_of_file_name("000012.h5"), Some(12));
        assert_eq!(step_of_file_name("1234567.h5"), Some(1_234_567));
        for other in ["000012.h5.part", "12.h5", "00001a.h5", "000012.xdmf", ".h5"] {
            assert_eq!(step_of_file_name(other), None, "{other}");
        }
    }

    #[test]
    fn sort_puts_node_fields_first_then_names() {
        let field = |name: &str, center| FieldDesc {
            name: name.into(),
            center,
            components: 1,
        };
        let mut m = XdmfModel {
            statics: vec![
                ("rank".into(), Center::Cell),
                ("node_id".into(), Center::Node),
                ("body".into(), Center::Cell),
                ("body".into(), Center::Node),
            ],
            fields: vec![
                field("stress", Center::Cell),
                field("temperature", Center::Node),
                field("displacement", Center::Node),
                field("owner_rank", Center::Cell),
            ],
            ..XdmfModel::default()
        };
        m.sort();
        let statics: Vec<_> = m.statics.iter().map(|(n, c)| (n.as_str(), *c)).collect();
        assert_eq!(
            statics,
            [
                ("body", Center::Node),
                ("node_id", Center::Node),
                ("body", Center::Cell),
                ("rank", Center::Cell)
            ]
        );
        let fields: Vec<_> = m.fields.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(
            fields,
            ["displacement", "temperature", "owner_rank", "stress"]
        );
    }
}
