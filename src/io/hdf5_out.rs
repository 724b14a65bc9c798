//! Collective HDF5 time-series writer (MPI-IO driver) and its XDMF index:
//! the mesh file and one file per output step, each written under a
//! `.part` name, closed, synced and then renamed; see the [module
//! documentation](super) for the layout and the crash-safety argument.

use std::path::{Path, PathBuf};

use hdf5::{File, Group};
use mpi::topology::SimpleCommunicator;
use mpi::traits::{Communicator, CommunicatorCollectives};

use super::ffi::{self, CollectiveXfer};
use super::xdmf::{self, Center, FieldDesc, XdmfModel};
use super::{
    check_name, hex_index_path, output_paths, remove_outputs, step_path, steps_dir, IoError,
};

/// This rank's part of a Tet4 mesh. Rows are distributed in contiguous blocks: the
/// non-empty blocks of all ranks must tile `0..global_nodes` (resp. `0..global_cells`)
/// exactly, in any rank order. A rank may own no nodes or no cells.
#[derive(Clone, Copy, Debug)]
pub struct MeshPart<'a> {
    /// Total number of nodes over all ranks.
    pub global_nodes: u64,
    /// This rank's owned nodes are rows `node_offset .. node_offset + coords.len()`.
    pub node_offset: u64,
    /// Coordinates of the owned nodes.
    pub coords: &'a [[f64; 3]],
    /// Total number of cells over all ranks.
    pub global_cells: u64,
    /// This rank's cells are rows `cell_offset .. cell_offset + cells.len()`.
    pub cell_offset: u64,
    /// Connectivity in GLOBAL node numbering (rows of `/mesh/coordinates`),
    /// `nodes_per_cell` entries per cell, flat.
    pub cells: &'a [u32],
    /// 4 (Tet4) or 3 (triangles).
    pub nodes_per_cell: usize,
    /// The Hex8 bodies' hexes (`/mesh/hexes`, the index `<stem>_hex8.xdmf`).
    pub hexes: Option<HexRows<'a>>,
}

/// This rank's block of `/mesh/hexes` `[H, 8]` u32 (global node ids, seed
/// 002 Table 1 order) and where each Hex8 body's hexes and tets are.
#[derive(Clone, Copy, Debug)]
pub struct HexRows<'a> {
    /// Number of hexes over all ranks.
    pub global: u64,
    /// This rank's rows are `offset .. offset + rows.len() / 8`.
    pub offset: u64,
    /// Eight global node ids per hex.
    pub rows: &'a [u32],
    /// The Hex8 bodies, the same on every rank.
    pub blocks: &'a [super::HexBlock],
}

impl MeshPart<'_> {
    /// This rank's number of cells.
    fn num_cells(&self) -> usize {
        self.cells.len() / self.nodes_per_cell.max(1)
    }
}

/// One field of one step: `(name, components, this rank's values)`.
pub type FieldData<'a> = (&'a str, usize, &'a [f64]);

/// The node and cell field lists of one step.
type FieldLists<'a, 'b> = [(Center, &'b [FieldData<'a>]); 2];

/// A contiguous block of rows owned by this rank.
#[derive(Clone, Copy, Debug)]
struct Rows {
    global: u64,
    offset: u64,
    count: u64,
}

mod checks;
mod files;
mod hexes;
mod reopen;

use checks::{agree, agree_signature, check_mesh_local, check_tiling, Fnv};
pub(crate) use files::part_path;
use files::{create_file, fixed_dataset, publish, remove_if_present};

/// The mesh file while it is written: open under `<stem>.h5.part` until the
/// first step (or the close) seals it.
struct OpenMesh {
    // Declared before `file` so that they are closed first.
    /// `/static/node`, `/static/cell` and, with hexes, `/static/hex`.
    static_groups: Vec<Group>,
    file: File,
    part: PathBuf,
}

/// The open state of a writer.
struct Inner {
    comm: SimpleCommunicator,
    rank: i32,
    h5_path: PathBuf,
    xdmf_path: PathBuf,
    nodes: Rows,
    cells: Rows,
    xfer: CollectiveXfer,
    /// The mesh file, while it is still being written.
    mesh: Option<OpenMesh>,
    /// The time-dependent fields, fixed by the first step, in the
    /// index's order ([`XdmfModel::sort`]).
    fields: Option<Vec<FieldDesc>>,
    model: XdmfModel,
    /// The hexes' rows of the cell fields this rank writes.
    hexes: Option<hexes::Sample>,
    usable: bool,
}

/// Collective writer of a time series: the mesh file `<dir>/<stem>.h5`, one
/// file per step `<dir>/<stem>_steps/<k:06>.h5` and the index
/// `<dir>/<stem>.xdmf`; see the [module documentation](super) for the
/// layout and crash-safety scheme.
///
/// Dropping the writer closes it like [`TimeSeriesWriter::close`], ignoring errors
/// (collectively, so every rank must drop it), except while panicking: then the
/// HDF5 handles are leaked instead of risking a collective call that other ranks
/// never make; the files keep the state of the last completed step.
pub struct TimeSeriesWriter {
    inner: Option<Inner>,
}

impl TimeSeriesWriter {
    /// Collective. Starts the series `<dir>/<stem>` (creating `dir` if
    /// missing; the outputs of an earlier run with the same stem are removed
    /// first) and writes the mesh: `/mesh/coordinates` `[N, 3]` f64 and
    /// `/mesh/topology` `[E, 4]` u32. The mesh file is written as
    /// `<stem>.h5.part`, takes the static fields, and is closed and renamed
    /// to `<stem>.h5` by the first [`write_step`](Self::write_step) (or by
    /// [`close`](Self::close) if no step is written), which also writes the
    /// XDMF file.
    ///
    /// The mesh distribution is validated on all ranks first; on any failure all
    /// ranks return an error and no output file is left behind.
    pub fn create(
        comm: &SimpleCommunicator,
        dir: &Path,
        stem: &str,
        mesh: &MeshPart,
    ) -> Result<Self, IoError> {
        let comm = comm.duplicate();
        let rank = comm.rank();
        let (h5_path, xdmf_path) = output_paths(dir, stem);

        // Validate: local checks, then a global view of the distribution.
        let local = check_name("file stem", stem)
            .and_then(|()| check_mesh_local(mesh))
            .and_then(|()| hexes::check_local(mesh));
        let hex = mesh.hexes.as_ref();
        let mine = [
            u64::from(local.is_ok()),
            mesh.global_nodes,
            mesh.node_offset,
            mesh.coords.len() as u64,
            mesh.global_cells,
            mesh.cell_offset,
            mesh.num_cells() as u64,
            hex.map_or(0, |h| h.global),
            hex.map_or(0, |h| h.offset),
            hex.map_or(0, |h| h.rows.len() as u64 / 8),
        ];
        let mut all = vec![0_u64; mine.len() * comm.size() as usize];
        comm.all_gather_into(&mine[..], &mut all[..]);
        local.map_err(|what| IoError::invalid(&h5_path, format!("mesh on rank {rank}: {what}")))?;
        let rows: Vec<&[u64]> = all.chunks(mine.len()).collect();
        if let Some(bad) = rows.iter().position(|r| r[0] == 0) {
            return Err(IoError::invalid(
                &h5_path,
                format!("mesh on rank {bad} is invalid (reported there)"),
            ));
        }
        if rows
            .iter()
            .any(|r| r[1] != mesh.global_nodes || r[4] != mesh.global_cells)
        {
            return Err(IoError::invalid(
                &h5_path,
                "ranks disagree on global_nodes or global_cells",
            ));
        }
        check_tiling(
            "node",
            mesh.global_nodes,
            rows.iter().map(|r| (r[2], r[3])).collect(),
        )
        .and_then(|()| {
            check_tiling(
                "cell",
                mesh.global_cells,
                rows.iter().map(|r| (r[5], r[6])).collect(),
            )
        })
        .and_then(|()| {
            let global = hex.map_or(0, |h| h.global);
            if rows.iter().any(|r| r[7] != global) {
                return Err("ranks disagree on the number of hexes".into());
            }
            check_tiling("hex", global, rows.iter().map(|r| (r[8], r[9])).collect())
        })
        .map_err(|what| IoError::invalid(&h5_path, what))?;

        // Rank 0 prepares the directory and removes the old series.
        let prepared = if rank == 0 {
            std::fs::create_dir_all(dir)
                .map_err(|e| IoError::io(dir, "creating output directory", e))
                .and_then(|()| {
                    remove_outputs(dir, stem).map_err(|e| {
                        IoError::invalid(&xdmf_path, format!("removing old outputs: {e}"))
                    })
                })
        } else {
            Ok(())
        };
        agree(&comm, &h5_path, "preparing the output directory", prepared)?;

        let nodes = Rows {
            global: mesh.global_nodes,
            offset: mesh.node_offset,
            count: mesh.coords.len() as u64,
        };
        let cells = Rows {
            global: mesh.global_cells,
            offset: mesh.cell_offset,
            count: mesh.num_cells() as u64,
        };
        let part = part_path(&h5_path);
        let created = CollectiveXfer::new()
            .map_err(|call| IoError::Hdf5Call {
                path: part.clone(),
                call,
                what: "creating a transfer property list".into(),
            })
            .and_then(|xfer| {
                let open = Inner::create_mesh(&comm, &part, &xfer, mesh, nodes, cells)?;
                Ok((xfer, open))
            });
        match agree(&comm, &h5_path, "creating the mesh file", created) {
            Ok((xfer, open)) => {
                let steps_name = steps_dir(&h5_path)
                    .file_name()
                    .unwrap_or_default()
                    .to_string_lossy()
                    .into_owned();
                Ok(Self {
                    inner: Some(Inner {
                        rank,
                        xdmf_path,
                        nodes,
                        cells,
                        xfer,
                        mesh: Some(open),
                        fields: None,
                        hexes: hex.map(|h| {
                            hexes::Sample::new(h.global, h.blocks, cells.offset, cells.count)
                        }),
                        model: XdmfModel {
                            h5_name: format!("{stem}.h5"),
                            steps_name,
                            nodes: nodes.global,
                            cells: cells.global,
                            nodes_per_cell: mesh.nodes_per_cell,
                            hexes: hex.map_or(0, |h| h.global),
                            hex_blocks: hex.map(|h| h.blocks.to_vec()).unwrap_or_default(),
                            ..XdmfModel::default()
                        },
                        usable: true,
                        h5_path,
                        comm,
                    }),
                })
            }
            Err(e) => {
                comm.barrier();
                if rank == 0 {
                    let _ = remove_outputs(dir, stem);
                }
                Err(e)
            }
        }
    }

    fn inner(&mut self) -> Result<&mut Inner, IoError> {
        match self.inner.as_mut() {
            Some(inner) if inner.usable => Ok(inner),
            Some(inner) => Err(IoError::Unusable {
                path: inner.h5_path.clone(),
            }),
            None => Err(IoError::Unusable {
                path: PathBuf::new(),
            }),
        }
    }

    /// Collective. Writes a static per-node i32 field `/static/node/<name>`
    /// (`values` = this rank's owned node rows) into the mesh file, before the
    /// first step. It appears in every step of the XDMF file.
    pub fn write_static_node_field_i32(
        &mut self,
        name: &str,
        values: &[i32],
    ) -> Result<(), IoError> {
        self.inner()?.write_static(Center::Node, name, values)
    }

    /// Collective. Writes a static per-cell i32 field `/static/cell/<name>`
    /// (`values` = this rank's cell rows) into the mesh file, before the
    /// first step. It appears in every step of the XDMF file.
    pub fn write_static_cell_field_i32(
        &mut self,
        name: &str,
        values: &[i32],
    ) -> Result<(), IoError> {
        self.inner()?.write_static(Center::Cell, name, values)
    }

    /// Collective. Appends one output step at `time` (finite, larger than the
    /// previous step's time), as the step file `<stem>_steps/<k:06>.h5`.
    ///
    /// Each entry `(name, components, values)` gives this rank's owned rows, row
    /// major: `values.len() == rows * components`, `components` in {1, 3, 6, 9}
    /// (scalar, vector, symmetric tensor in XDMF `Tensor6` order xx, xy, xz,
    /// yy, yz, zz (see [`super::tensor6`]), full tensor).
    /// The first call fixes the set of node and cell fields; later calls must pass
    /// the same names with the same component counts (in any order).
    ///
    /// When this returns `Ok`, the step file is closed, synced and in place,
    /// and listed in the XDMF file. After an HDF5 error the writer refuses
    /// further steps; the files keep the state of the last completed step.
    pub fn write_step(
        &mut self,
        time: f64,
        node_fields: &[(&str, usize, &[f64])],
        cell_fields: &[(&str, usize, &[f64])],
    ) -> Result<(), IoError> {
        self.inner()?.write_step(time, node_fields, cell_fields)
    }

    /// Number of completed steps.
    pub fn steps(&self) -> usize {
        self.inner.as_ref().map_or(0, |i| i.model.times.len())
    }

    /// Path of the mesh file `<stem>.h5` (the series' name for the readers).
    pub fn h5_path(&self) -> &Path {
        self.inner.as_ref().map_or(Path::new(""), |i| &i.h5_path)
    }

    /// Path of the XDMF file.
    pub fn xdmf_path(&self) -> &Path {
        self.inner.as_ref().map_or(Path::new(""), |i| &i.xdmf_path)
    }

    /// Collective. Seals the mesh file if no step did, and closes the writer.
    /// If no step was written, the XDMF file lists the mesh and its static
    /// fields without time.
    pub fn close(mut self) -> Result<(), IoError> {
        match self.inner.take() {
            Some(inner) => inner.finish(),
            None => Ok(()),
        }
    }
}

impl Drop for TimeSeriesWriter {
    fn drop(&mut self) {
        if let Some(inner) = self.inner.take() {
            if std::thread::panicking() {
                std::mem::forget(inner);
            } else {
                let _ = inner.finish();
            }
        }
    }
}

impl Inner {
    /// Creates the mesh file `part`, its groups and the mesh datasets. Collective.
    fn create_mesh(
        comm: &SimpleCommunicator,
        part: &Path,
        xfer: &CollectiveXfer,
        mesh: &MeshPart,
        nodes: Rows,
        cells: Rows,
    ) -> Result<OpenMesh, IoError> {
        let h5err = |what: &str| {
            let what = what.to_string();
            move |e| IoError::hdf5(part, what, e)
        };
        let call = |what: &str| {
            let what = what.to_string();
            move |call| IoError::Hdf5Call {
                path: part.to_path_buf(),
                call,
                what,
            }
        };
        let file = create_file(comm, part)?;
        let group = |parent: &Group, name: &str| {
            parent
                .create_group(name)
                .map_err(h5err(&format!("creating group {name}")))
        };
        let mesh_g = group(&file, "mesh")?;
        let static_g = group(&file, "static")?;
        let mut static_groups = vec![group(&static_g, "node")?, group(&static_g, "cell")?];
        if mesh.hexes.is_some() {
            static_groups.push(group(&static_g, "hex")?);
        }
        let coords = fixed_dataset::<f64>(&mesh_g, "coordinates", &[nodes.global, 3])
            .map_err(h5err("creating /mesh/coordinates"))?;
        ffi::write_block(
            &coords,
            xfer,
            &[nodes.offset, 0],
            &[nodes.count, 3],
            mesh.coords.as_flattened(),
        )
        .map_err(call("writing /mesh/coordinates"))?;
        let npc = mesh.nodes_per_cell as u64;
        let topo = fixed_dataset::<u32>(&mesh_g, "topology", &[cells.global, npc])
            .map_err(h5err("creating /mesh/topology"))?;
        ffi::write_block(
            &topo,
            xfer,
            &[cells.offset, 0],
            &[cells.count, npc],
            mesh.cells,
        )
        .map_err(call("writing /mesh/topology"))?;
        if let Some(h) = &mesh.hexes {
            hexes::write(part, &mesh_g, xfer, h)?;
        }
        drop((coords, topo, mesh_g, static_g));
        Ok(OpenMesh {
            static_groups,
            file,
            part: part.to_path_buf(),
        })
    }

    fn rows(&self, center: Center) -> Rows {
        match center {
            Center::Node => self.nodes,
            Center::Cell => self.cells,
        }
    }

    fn group_index(center: Center) -> usize {
        match center {
            Center::Node => 0,
            Center::Cell => 1,
        }
    }

    fn write_static(&mut self, center: Center, name: &str, values: &[i32]) -> Result<(), IoError> {
        let rows = self.rows(center);
        let what = format!("writing static {} field {name:?}", center.group());
        let local = check_name("static field", name)
            .and_then(|()| {
                if self.mesh.is_none() {
                    Err(format!(
                        "static {} field {name:?}: static fields are written before the first step",
                        center.group()
                    ))
                } else if self.model.statics.iter().any(|(n, c)| n == name && *c == center) {
                    Err(format!("static {} field {name:?} was already written", center.group()))
                } else if values.len() as u64 != rows.count {
                    Err(format!(
                        "static {} field {name:?} has {} values on rank {}, expected {} (owned rows)",
                        center.group(),
                        values.len(),
                        self.rank,
                        rows.count
                    ))
                } else {
                    Ok(())
                }
            })
            .map_err(|w| IoError::invalid(&self.h5_path, w));
        let sig = Fnv::new().str(name).u64(Self::group_index(center) as u64).0;
        agree_signature(&self.comm, &self.h5_path, &what, local, sig)?;

        let open = self
            .mesh
            .as_ref()
            .unwrap_or_else(|| unreachable!("checked above"));
        let result = (|| {
            let group = &open.static_groups[Self::group_index(center)];
            let ds = fixed_dataset::<i32>(group, name, &[rows.global]).map_err(|e| {
                IoError::hdf5(
                    &open.part,
                    format!("creating /static/{}/{name}", center.group()),
                    e,
                )
            })?;
            ffi::write_block(&ds, &self.xfer, &[rows.offset], &[rows.count], values).map_err(
                |call| IoError::Hdf5Call {
                    path: open.part.clone(),
                    call,
                    what: what.clone(),
                },
            )?;
            match (&self.hexes, center) {
                (Some(h), Center::Cell) => h.write(
                    &open.part,
                    &open.static_groups[2],
                    &self.xfer,
                    (name, 1, values),
                ),
                _ => Ok(()),
            }
        })();
        let result = agree(&self.comm, &self.h5_path, &what, result);
        if result.is_err() {
            self.usable = false;
            return result;
        }
        self.model.statics.push((name.to_string(), center));
        self.model.sort();
        Ok(())
    }

    fn write_step(
        &mut self,
        time: f64,
        node_fields: &[(&str, usize, &[f64])],
        cell_fields: &[(&str, usize, &[f64])],
    ) -> Result<(), IoError> {
        let step = self.model.times.len();
        let what = format!("writing step {step} (time {time:e})");
        let lists = [(Center::Node, node_fields), (Center::Cell, cell_fields)];
        let local = self
            .check_step(time, lists)
            .map_err(|w| IoError::invalid(&self.h5_path, format!("step {step}: {w}")));
        let mut sig = Fnv::new().u64(time.to_bits());
        for (center, list) in lists {
            for &(name, comps, _) in list {
                sig = sig
                    .u64(Self::group_index(center) as u64)
                    .str(name)
                    .u64(comps as u64);
            }
        }
        agree_signature(&self.comm, &self.h5_path, &what, local, sig.0)?;

        // The mesh file is complete: seal it, and make room for the steps.
        self.seal_mesh()?;
        if step == 0 {
            let dir = steps_dir(&self.h5_path);
            let made = if self.rank == 0 {
                std::fs::create_dir_all(&dir)
                    .map_err(|e| IoError::io(&dir, "creating the step directory", e))
            } else {
                Ok(())
            };
            let made = agree(&self.comm, &dir, "creating the step directory", made);
            if made.is_err() {
                self.usable = false;
                return made;
            }
        }
        if self.fields.is_none() {
            let mut model = XdmfModel {
                fields: lists
                    .iter()
                    .flat_map(|&(center, list)| {
                        list.iter().map(move |&(name, components, _)| FieldDesc {
                            name: name.to_string(),
                            center,
                            components,
                        })
                    })
                    .collect(),
                ..XdmfModel::default()
            };
            model.sort();
            self.model.fields.clone_from(&model.fields);
            self.fields = Some(model.fields);
        }

        // The step file: written as `.part`, closed by every rank, then
        // synced and renamed by rank 0.
        let path = step_path(&self.h5_path, step);
        let part = part_path(&path);
        let written = self.write_step_file(&part, time, lists);
        let written = agree(&self.comm, &path, &what, written);
        let published = written.and_then(|()| {
            let published = if self.rank == 0 {
                publish(&part, &path)
            } else {
                Ok(())
            };
            agree(&self.comm, &path, &what, published)
        });
        if published.is_err() {
            if self.rank == 0 {
                let _ = remove_if_present(&part);
            }
            self.usable = false;
            return published;
        }
        self.model.times.push(time);
        self.write_index()
    }

    /// Writes every field of one step and its time into the new file `part`,
    /// and closes it. Collective.
    fn write_step_file(
        &self,
        part: &Path,
        time: f64,
        lists: FieldLists<'_, '_>,
    ) -> Result<(), IoError> {
        let h5err = |what: String| move |e| IoError::hdf5(part, what, e);
        let call = |what: String| {
            move |call| IoError::Hdf5Call {
                path: part.to_path_buf(),
                call,
                what,
            }
        };
        let file = create_file(&self.comm, part)?;
        let written = (|| {
            let fields_g = file
                .create_group("fields")
                .map_err(h5err("creating group /fields".into()))?;
            let mut groups = Vec::new();
            let hex = self.hexes.as_ref().map(|_| "hex");
            for name in [Center::Node.group(), Center::Cell.group()]
                .into_iter()
                .chain(hex)
            {
                groups.push(
                    fields_g
                        .create_group(name)
                        .map_err(h5err(format!("creating group /fields/{name}")))?,
                );
            }
            let fields = self.fields.as_deref().unwrap_or_default();
            for d in fields {
                let what = format!("writing /fields/{}/{}", d.center.group(), d.name);
                let rows = self.rows(d.center);
                let values = lists[Self::group_index(d.center)]
                    .1
                    .iter()
                    .find(|f| f.0 == d.name)
                    .map(|f| f.2)
                    .unwrap_or_else(|| unreachable!("field set checked before"));
                let comps = d.components as u64;
                let (shape, start, count) = if comps == 1 {
                    (vec![rows.global], vec![rows.offset], vec![rows.count])
                } else {
                    (
                        vec![rows.global, comps],
                        vec![rows.offset, 0],
                        vec![rows.count, comps],
                    )
                };
                let group = &groups[Self::group_index(d.center)];
                let ds =
                    fixed_dataset::<f64>(group, &d.name, &shape).map_err(h5err(what.clone()))?;
                ffi::write_block(&ds, &self.xfer, &start, &count, values).map_err(call(what))?;
                if let (Some(h), Center::Cell) = (&self.hexes, d.center) {
                    h.write(
                        part,
                        &groups[2],
                        &self.xfer,
                        (&d.name, d.components, values),
                    )?;
                }
            }
            let time_ds = fixed_dataset::<f64>(&file, "time", &[1])
                .map_err(h5err("creating /time".into()))?;
            let (count, data): (u64, &[f64]) = if self.rank == 0 {
                (1, &[time])
            } else {
                (0, &[])
            };
            ffi::write_block(&time_ds, &self.xfer, &[0], &[count], data)
                .map_err(call("writing /time".into()))
        })();
        let closed = file.close().map_err(h5err("closing the step file".into()));
        written.and(closed)
    }

    /// Collective. Closes the mesh file, if it is still open, and renames it
    /// into place; then the step files and the index may refer to it.
    fn seal_mesh(&mut self) -> Result<(), IoError> {
        let Some(OpenMesh {
            static_groups,
            file,
            part,
        }) = self.mesh.take()
        else {
            return Ok(());
        };
        drop(static_groups);
        let closed = file
            .close()
            .map_err(|e| IoError::hdf5(&part, "closing the mesh file", e));
        let what = "sealing the mesh file";
        let sealed = agree(&self.comm, &self.h5_path, what, closed).and_then(|()| {
            let published = if self.rank == 0 {
                publish(&part, &self.h5_path)
            } else {
                Ok(())
            };
            agree(&self.comm, &self.h5_path, what, published)
        });
        if sealed.is_err() {
            if self.rank == 0 {
                let _ = remove_if_present(&part);
            }
            self.usable = false;
        }
        sealed
    }

    /// Collective. Rank 0 replaces the XDMF file (`.tmp` and rename) by one
    /// listing the steps completed so far (the mesh alone if there is none).
    /// Every file it names is in place.
    fn write_index(&self) -> Result<(), IoError> {
        let indexed = if self.rank == 0 {
            xdmf::write_atomic(&self.xdmf_path, &self.model.render()).and_then(|()| {
                match self.model.render_hexes() {
                    Some(text) => xdmf::write_atomic(&hex_index_path(&self.xdmf_path), &text),
                    None => Ok(()),
                }
            })
        } else {
            Ok(())
        };
        agree(
            &self.comm,
            &self.xdmf_path,
            "writing the XDMF file",
            indexed,
        )
    }

    /// Collective. Seals the mesh file if no step did (and then writes the
    /// mesh-only XDMF file), and closes. A mesh file left open by an error is
    /// closed and its `.part` removed.
    fn finish(mut self) -> Result<(), IoError> {
        let mut result = Ok(());
        if self.usable {
            let first_seal = self.mesh.is_some();
            result = self.seal_mesh();
            if result.is_ok() && first_seal && self.model.times.is_empty() {
                result = self.write_index();
            }
        }
        if let Some(open) = self.mesh.take() {
            drop(open.static_groups);
            let _ = open.file.close();
            if self.rank == 0 {
                let _ = remove_if_present(&open.part);
            }
        }
        result
    }
}

#[cfg(test)]
mod tests {
    use super::super::{read_cell_field_step, read_node_field_step, read_static_node_field_i32};
    use super::super::{read_mesh, read_times};
    use super::*;
    use crate::testutil::on_one_rank;

    const COORDS: [[f64; 3]; 5] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
    ];
    const CELLS: [u32; 8] = [0, 1, 2, 3, 1, 2, 3, 4];

    fn mesh() -> MeshPart<'static> {
        MeshPart {
            global_nodes: 5,
            node_offset: 0,
            coords: &COORDS,
            global_cells: 2,
            cell_offset: 0,
            cells: &CELLS,
            nodes_per_cell: 4,
            hexes: None,
        }
    }

    /// Node temperature `t + row` and cell stress rows `t * (row + 1)` at time `t`.
    fn step(w: &mut TimeSeriesWriter, t: f64) -> Result<(), IoError> {
        let temp: Vec<f64> = (0..5).map(|r| t + f64::from(r)).collect();
        let stress: Vec<f64> = (0..12).map(|i| t * f64::from(i / 6 + 1)).collect();
        w.write_step(t, &[("temperature", 1, &temp)], &[("stress", 6, &stress)])
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .map(|d| {
                d.flatten()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .collect()
            })
            .unwrap_or_default();
        v.sort();
        v
    }

    fn listed(xdmf: &Path) -> usize {
        std::fs::read_to_string(xdmf)
            .unwrap()
            .matches("<Time ")
            .count()
    }

    #[test]
    fn each_file_appears_complete_under_its_final_name() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        on_one_rank(|comm| {
            let mut w = TimeSeriesWriter::create(comm, d, "s", &mesh()).unwrap();
            w.write_static_node_field_i32("node_id", &[0, 1, 2, 3, 4])
                .unwrap();
            // The mesh file is still being written: only its `.part` exists.
            assert_eq!(names(d), ["s.h5.part"]);
            for (k, t) in [0.0, 0.5, 1.0].into_iter().enumerate() {
                step(&mut w, t).unwrap();
                assert_eq!(names(d), ["s.h5", "s.xdmf", "s_steps"]);
                let files: Vec<String> = (0..=k).map(xdmf::step_file_name).collect();
                assert_eq!(names(&d.join("s_steps")), files);
                assert_eq!(listed(&d.join("s.xdmf")), k + 1);
            }
            // Static fields belong to the mesh file, written before the steps.
            let e = w
                .write_static_cell_field_i32("late", &[1, 2])
                .unwrap_err()
                .to_string();
            assert!(e.contains("before the first step"), "{e}");
            step(&mut w, 1.5).unwrap();
            w.close().unwrap();
        });
        let h5 = d.join("s.h5");
        assert_eq!(read_times(&h5).unwrap(), [0.0, 0.5, 1.0, 1.5]);
        assert_eq!(read_mesh(&h5).unwrap().coords, COORDS);
        assert_eq!(
            read_static_node_field_i32(&h5, "node_id").unwrap(),
            [0, 1, 2, 3, 4]
        );
        assert_eq!(
            read_node_field_step(&h5, "temperature", 2).unwrap(),
            [1.0, 2.0, 3.0, 4.0, 5.0]
        );
        let s = read_cell_field_step(&h5, "stress", 3).unwrap();
        assert_eq!(s.len(), 12);
        assert!(s[..6].iter().all(|&v| v == 1.5) && s[6..].iter().all(|&v| v == 3.0));
        let e = read_node_field_step(&h5, "temperature", 4)
            .unwrap_err()
            .to_string();
        assert!(e.contains("the series has 4 steps"), "{e}");
        let text = std::fs::read_to_string(d.join("s.xdmf")).unwrap();
        assert!(text.contains(">s_steps/000003.h5:/fields/cell/stress</DataItem>"));
        assert!(text.contains(">s.h5:/static/node/node_id</DataItem>"));
    }

    #[test]
    fn a_series_without_steps_indexes_its_mesh() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        on_one_rank(|comm| {
            let w = TimeSeriesWriter::create(comm, d, "m", &mesh()).unwrap();
            w.close().unwrap();
        });
        assert_eq!(names(d), ["m.h5", "m.xdmf"]);
        assert_eq!(listed(&d.join("m.xdmf")), 0);
        assert!(read_times(&d.join("m.h5")).unwrap().is_empty());
    }

    #[test]
    fn create_removes_an_old_series_and_its_leftovers() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let steps = d.join("s_steps");
        std::fs::create_dir_all(&steps).unwrap();
        for f in ["000000.h5", "000007.h5", "000008.h5.part"] {
            std::fs::write(steps.join(f), "old").unwrap();
        }
        for f in ["s.h5", "s.xdmf", "s.xdmf.tmp", "s.h5.part", "other.h5"] {
            std::fs::write(d.join(f), "old").unwrap();
        }
        on_one_rank(|comm| {
            let mut w = TimeSeriesWriter::create(comm, d, "s", &mesh()).unwrap();
            assert_eq!(names(d), ["other.h5", "s.h5.part"]);
            step(&mut w, 0.0).unwrap();
            w.close().unwrap();
        });
        assert_eq!(names(&steps), ["000000.h5"]);
        assert_eq!(read_times(&d.join("s.h5")).unwrap(), [0.0]);
    }

    #[test]
    fn reopen_keeps_the_steps_up_to_the_checkpoint() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let ids = [0, 1, 2, 3, 4];
        on_one_rank(|comm| {
            let mut w = TimeSeriesWriter::create(comm, d, "s", &mesh()).unwrap();
            w.write_static_node_field_i32("node_id", &ids).unwrap();
            w.write_static_cell_field_i32("body", &[0, 0]).unwrap();
            for t in [0.0, 1.0, 2.0, 3.0] {
                step(&mut w, t).unwrap();
            }
            w.close().unwrap();
        });
        let first = std::fs::read_to_string(d.join("s.xdmf")).unwrap();
        // A killed run's leftover.
        std::fs::write(d.join("s_steps/000004.h5.part"), "partial").unwrap();
        on_one_rank(|comm| {
            let mut w = TimeSeriesWriter::reopen(comm, d, "s", &mesh(), &ids, 1.0).unwrap();
            assert_eq!(w.steps(), 2);
            assert_eq!(listed(&d.join("s.xdmf")), 2);
            assert_eq!(names(&d.join("s_steps")), ["000000.h5", "000001.h5"]);
            // The field set is the series': another one is refused.
            let e = w
                .write_step(1.5, &[("other", 1, &[0.0; 5])], &[])
                .unwrap_err()
                .to_string();
            assert!(e.contains("missing"), "{e}");
            for t in [2.0, 3.0] {
                step(&mut w, t).unwrap();
            }
            w.close().unwrap();
        });
        // Continued, the series is the uninterrupted one, index included.
        assert_eq!(read_times(&d.join("s.h5")).unwrap(), [0.0, 1.0, 2.0, 3.0]);
        assert_eq!(std::fs::read_to_string(d.join("s.xdmf")).unwrap(), first);
        // Other rows (another partition) are refused, naming the reason.
        let e = on_one_rank(|comm| {
            TimeSeriesWriter::reopen(comm, d, "s", &mesh(), &[1, 0, 2, 3, 4], 1.0)
                .err()
                .unwrap()
                .to_string()
        });
        assert!(e.contains("another order"), "{e}");
    }
}
