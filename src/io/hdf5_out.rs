//! Collective HDF5 time-series writer (MPI-IO driver) and its XDMF index.

use std::path::{Path, PathBuf};

use hdf5::plist::dataset_create::{AllocTime, FillTime};
use hdf5::{Dataset, Extent, File, Group, H5Type, SimpleExtents};
use mpi::collective::SystemOperation;
use mpi::raw::AsRaw as _;
use mpi::topology::SimpleCommunicator;
use mpi::traits::{Communicator, CommunicatorCollectives};

use super::ffi::{self, CollectiveXfer};
use super::xdmf::{self, Center, FieldDesc, XdmfModel};
use super::{check_name, output_paths, remove_outputs, IoError};

/// Initial local-heap size of a field's step group: room for the link names of
/// this many steps before the heap has to be moved (and its old block freed).
const STEP_NAMES_RESERVED: usize = 16_384;
/// Half the capacity of a symbol-table leaf node (HDF5 default 4).
const SYMBOL_LEAF_K: u32 = 256;
/// Chunk length of `/time`.
const TIME_CHUNK: usize = 512;

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
use checks::{agree, agree_signature, check_mesh_local, check_tiling, Fnv};

/// A time-dependent field and the group holding its per-step datasets.
struct FieldSlot {
    desc: FieldDesc,
    group: Group,
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
    // Datasets and groups are declared before `file` so they are closed first.
    fields: Option<Vec<FieldSlot>>,
    time_ds: Dataset,
    static_groups: [Group; 2],
    field_groups: [Group; 2],
    file: File,
    model: XdmfModel,
    usable: bool,
    /// While the file is still `<stem>.h5.part`: it is renamed to
    /// `<stem>.h5` by the first [`Inner::publish`] of a step (or by
    /// [`Inner::finish`]), so that the first step's groups and heaps, the
    /// largest metadata flush of the run, are written before the name exists.
    pending: Option<PathBuf>,
}

/// Collective writer of a time series `<dir>/<stem>.h5` + `<dir>/<stem>.xdmf`; see
/// the [module documentation](super) for the file layout and crash-safety scheme.
///
/// Dropping the writer closes it like [`TimeSeriesWriter::close`], ignoring errors
/// (collectively, so every rank must drop it), except while panicking: then the
/// HDF5 handles are leaked instead of risking a collective call that other ranks
/// never make; the files keep the state of the last completed step.
pub struct TimeSeriesWriter {
    inner: Option<Inner>,
}

impl TimeSeriesWriter {
    /// Collective. Creates `<dir>/<stem>.h5` (and `dir`, if missing) and writes the
    /// mesh: `/mesh/coordinates` `[N, 3]` f64 and `/mesh/topology` `[E, 4]` u32.
    /// Outputs of an earlier run with the same stem are removed first. The file is
    /// written as `<stem>.h5.part` and renamed once the first step (or, if no
    /// step is written, the closing flush) is on disk. The XDMF file is written
    /// by the first [`write_step`](Self::write_step) (or by
    /// [`close`](Self::close) if no step is written).
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
        let local = check_name("file stem", stem).and_then(|()| check_mesh_local(mesh));
        let mine = [
            u64::from(local.is_ok()),
            mesh.global_nodes,
            mesh.node_offset,
            mesh.coords.len() as u64,
            mesh.global_cells,
            mesh.cell_offset,
            mesh.num_cells() as u64,
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
        .map_err(|what| IoError::invalid(&h5_path, what))?;

        // Rank 0 prepares the directory and removes a stale index.
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
        let h5_name = format!("{stem}.h5");
        // The file is built under `<stem>.h5.part` and renamed by the first
        // step's publish, so `<stem>.h5` never names a file without a complete
        // mesh and first step.
        let part_path = part_path(&h5_path);
        let created = Inner::create(&comm, &part_path, mesh, nodes, cells);
        let created = agree(&comm, &h5_path, "creating the HDF5 file", created);
        match created {
            Ok((file, xfer, time_ds, static_groups, field_groups)) => Ok(Self {
                inner: Some(Inner {
                    rank,
                    xdmf_path,
                    nodes,
                    cells,
                    xfer,
                    fields: None,
                    time_ds,
                    static_groups,
                    field_groups,
                    file,
                    model: XdmfModel {
                        h5_name,
                        nodes: nodes.global,
                        cells: cells.global,
                        nodes_per_cell: mesh.nodes_per_cell,
                        ..XdmfModel::default()
                    },
                    usable: true,
                    pending: Some(part_path),
                    h5_path,
                    comm,
                }),
            }),
            Err(e) => {
                comm.barrier();
                if rank == 0 {
                    let _ = remove_outputs(dir, stem);
                }
                Err(e)
            }
        }
    }

    /// Collective. Reopens the series `<dir>/<stem>.h5` of an earlier run to
    /// continue it (a restart in place): keeps the steps with times up to
    /// `keep_until` (the checkpoint's time), removes the later ones and
    /// returns a writer that appends after them. The file must hold the same
    /// mesh in the same row order (`mesh` and this rank's original node ids
    /// `node_ids` are compared with the file's rows): a series written with
    /// another partition, for example on another number of ranks, is an
    /// error saying so. Static fields are kept as they are.
    pub fn reopen(
        comm: &SimpleCommunicator,
        dir: &Path,
        stem: &str,
        mesh: &MeshPart,
        node_ids: &[i32],
        keep_until: f64,
    ) -> Result<Self, IoError> {
        let comm = comm.duplicate();
        let rank = comm.rank();
        let (h5_path, xdmf_path) = output_paths(dir, stem);
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
        let path = h5_path.clone();
        let h5err = |what: &str| {
            let what = what.to_string();
            let path = path.clone();
            move |e| IoError::hdf5(&path, what, e)
        };
        let opened = File::with_options()
            .with_fapl(|p| p.mpio(comm.as_raw(), None))
            .open_rw(&h5_path)
            .map_err(h5err("reopening the series to continue it"));
        let file = agree(&comm, &h5_path, "reopening the series", opened)?;
        // Same mesh, same rows: this rank's block of node ids and cells.
        let check = (|| -> Result<Option<String>, IoError> {
            let coords = file
                .dataset("mesh/coordinates")
                .map_err(h5err("opening /mesh/coordinates"))?;
            let topo = file
                .dataset("mesh/topology")
                .map_err(h5err("opening /mesh/topology"))?;
            if coords.shape() != [nodes.global as usize, 3]
                || topo.shape() != [cells.global as usize, mesh.nodes_per_cell]
            {
                return Ok(Some(format!(
                    "it holds a mesh of {:?} nodes and {:?} cells, this run {} and {}",
                    coords.shape(),
                    topo.shape(),
                    nodes.global,
                    cells.global
                )));
            }
            let ids = file
                .dataset("static/node/node_id")
                .and_then(|d| {
                    d.read_slice_1d::<i32, _>(
                        nodes.offset as usize..(nodes.offset + nodes.count) as usize,
                    )
                })
                .map_err(h5err("reading /static/node/node_id"))?;
            let t = topo
                .read_slice_2d::<u32, _>((
                    cells.offset as usize..(cells.offset + cells.count) as usize,
                    ..,
                ))
                .map_err(h5err("reading /mesh/topology"))?;
            let same_cells = t.as_slice().is_some_and(|v| v == mesh.cells);
            if ids.as_slice() != Some(node_ids) || !same_cells {
                return Ok(Some(
                    "its rows are in another order (another partition, or another number of ranks)"
                        .into(),
                ));
            }
            Ok(None)
        })();
        let check = agree(&comm, &h5_path, "checking the series to continue", check)?;
        let mismatch = i32::from(check.is_some());
        let mut any = 0;
        comm.all_reduce_into(&mismatch, &mut any, SystemOperation::max());
        if any != 0 {
            return Err(IoError::invalid(
                &h5_path,
                format!(
                    "cannot continue this series in place: {}; restart into another output \
                     directory (--output), or on the rank count that wrote it",
                    check.unwrap_or_else(|| "another rank's rows differ".into())
                ),
            ));
        }
        let built = (|| -> Result<Inner, IoError> {
            let time_ds = file.dataset("time").map_err(h5err("opening /time"))?;
            let times: Vec<f64> = time_ds.read_raw().map_err(h5err("reading /time"))?;
            let tol = 1e-9 * keep_until.abs().max(1.0);
            let keep = times.iter().take_while(|&&t| t <= keep_until + tol).count();
            let group = |name: &str| file.group(name).map_err(h5err(&format!("opening /{name}")));
            let static_groups = [group("static/node")?, group("static/cell")?];
            let field_groups = [group("fields/node")?, group("fields/cell")?];
            let mut statics = Vec::new();
            for (g, center) in static_groups.iter().zip([Center::Node, Center::Cell]) {
                for name in g.member_names().map_err(h5err("listing static fields"))? {
                    statics.push((name, center));
                }
            }
            let mut slots = Vec::new();
            for (g, center) in field_groups.iter().zip([Center::Node, Center::Cell]) {
                for name in g.member_names().map_err(h5err("listing fields"))? {
                    let fg = g
                        .group(&name)
                        .map_err(h5err(&format!("opening field {name}")))?;
                    let first = fg
                        .dataset(&xdmf::step_name(0))
                        .map_err(h5err(&format!("opening field {name}, step 0")))?;
                    let shape = first.shape();
                    let components = if shape.len() == 1 { 1 } else { shape[1] };
                    // Drop the steps after the checkpoint.
                    for k in keep..times.len() {
                        let step = xdmf::step_name(k);
                        if fg.link_exists(&step) {
                            fg.unlink(&step)
                                .map_err(h5err(&format!("removing field {name} step {k}")))?;
                        }
                    }
                    slots.push(FieldSlot {
                        desc: FieldDesc {
                            name,
                            center,
                            components,
                        },
                        group: fg,
                    });
                }
            }
            time_ds.resize(keep).map_err(h5err("truncating /time"))?;
            let xfer = CollectiveXfer::new().map_err(|call| IoError::Hdf5Call {
                path: h5_path.clone(),
                call,
                what: "creating a transfer property list".into(),
            })?;
            let fields = (!slots.is_empty()).then_some(slots);
            Ok(Inner {
                rank,
                xdmf_path: xdmf_path.clone(),
                nodes,
                cells,
                xfer,
                model: XdmfModel {
                    h5_name: format!("{stem}.h5"),
                    nodes: nodes.global,
                    cells: cells.global,
                    nodes_per_cell: mesh.nodes_per_cell,
                    statics,
                    fields: fields.as_ref().map_or(Vec::new(), |f: &Vec<FieldSlot>| {
                        f.iter().map(|s| s.desc.clone()).collect()
                    }),
                    times: times[..keep].to_vec(),
                },
                fields,
                time_ds,
                static_groups,
                field_groups,
                file: file.clone(),
                usable: true,
                pending: None,
                h5_path: h5_path.clone(),
                comm: comm.duplicate(),
            })
        })();
        let mut inner = agree(
            &comm,
            &h5_path,
            "truncating the series to the checkpoint",
            built,
        )?;
        inner.publish("continuing the series")?;
        Ok(Self { inner: Some(inner) })
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
    /// (`values` = this rank's owned node rows). It appears in every step of the
    /// XDMF file.
    pub fn write_static_node_field_i32(
        &mut self,
        name: &str,
        values: &[i32],
    ) -> Result<(), IoError> {
        self.inner()?.write_static(Center::Node, name, values)
    }

    /// Collective. Writes a static per-cell i32 field `/static/cell/<name>`
    /// (`values` = this rank's cell rows). It appears in every step of the XDMF file.
    pub fn write_static_cell_field_i32(
        &mut self,
        name: &str,
        values: &[i32],
    ) -> Result<(), IoError> {
        self.inner()?.write_static(Center::Cell, name, values)
    }

    /// Collective. Appends one output step at `time` (finite, larger than the
    /// previous step's time).
    ///
    /// Each entry `(name, components, values)` gives this rank's owned rows, row
    /// major: `values.len() == rows * components`, `components` in {1, 3, 6, 9}
    /// (scalar, vector, symmetric tensor in XDMF `Tensor6` order xx, xy, xz,
    /// yy, yz, zz (see [`super::tensor6`]), full tensor).
    /// The first call fixes the set of node and cell fields; later calls must pass
    /// the same names with the same component counts (in any order).
    ///
    /// When this returns `Ok`, the step is flushed to disk and listed in the XDMF
    /// file. After an HDF5 error the writer refuses further steps; the files keep
    /// the state of the last completed step.
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

    /// Path of the HDF5 file.
    pub fn h5_path(&self) -> &Path {
        self.inner.as_ref().map_or(Path::new(""), |i| &i.h5_path)
    }

    /// Path of the XDMF file.
    pub fn xdmf_path(&self) -> &Path {
        self.inner.as_ref().map_or(Path::new(""), |i| &i.xdmf_path)
    }

    /// Collective. Flushes and closes the files. If no step was written, the XDMF
    /// file lists the mesh and its static fields without time.
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

type Created = (File, CollectiveXfer, Dataset, [Group; 2], [Group; 2]);

impl Inner {
    /// Creates the file, its groups, `/time` and the mesh datasets. Collective.
    fn create(
        comm: &SimpleCommunicator,
        path: &Path,
        mesh: &MeshPart,
        nodes: Rows,
        cells: Rows,
    ) -> Result<Created, IoError> {
        let h5err = |what: &str| {
            let what = what.to_string();
            move |e| IoError::hdf5(path, what, e)
        };
        let call = |what: &str| {
            let what = what.to_string();
            move |call| IoError::Hdf5Call {
                path: path.to_path_buf(),
                call,
                what,
            }
        };
        let file = File::with_options()
            .with_fapl(|p| p.mpio(comm.as_raw(), None))
            // Symbol-table leaves of up to 2 * 256 links: a step group's leaf is
            // split (new leaf + B-tree update) only every few hundred steps.
            .with_fcpl(|p| p.sym_k(16, SYMBOL_LEAF_K))
            .create(path)
            .map_err(h5err("creating the file with the MPI-IO driver"))?;
        let xfer = CollectiveXfer::new().map_err(call("creating a transfer property list"))?;
        let group = |parent: &Group, name: &str| {
            parent
                .create_group(name)
                .map_err(h5err(&format!("creating group {name}")))
        };
        let mesh_g = group(&file, "mesh")?;
        let static_g = group(&file, "static")?;
        let fields_g = group(&file, "fields")?;
        let static_groups = [group(&static_g, "node")?, group(&static_g, "cell")?];
        let field_groups = [group(&fields_g, "node")?, group(&fields_g, "cell")?];

        let time_ds = file
            .new_dataset::<f64>()
            .shape(SimpleExtents::new([Extent::resizable(0)]))
            .chunk([TIME_CHUNK])
            .alloc_time(Some(AllocTime::Early))
            .fill_time(FillTime::Never)
            .create("time")
            .map_err(h5err("creating /time"))?;

        let coords = fixed_dataset::<f64>(&mesh_g, "coordinates", &[nodes.global, 3])
            .map_err(h5err("creating /mesh/coordinates"))?;
        ffi::write_block(
            &coords,
            &xfer,
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
            &xfer,
            &[cells.offset, 0],
            &[cells.count, npc],
            mesh.cells,
        )
        .map_err(call("writing /mesh/topology"))?;
        drop((coords, topo, mesh_g, static_g, fields_g));
        ffi::flush_global(&file).map_err(call("flushing after writing the mesh"))?;
        Ok((file, xfer, time_ds, static_groups, field_groups))
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

    fn call_err(&self, what: &str) -> impl Fn(ffi::CallError) -> IoError + '_ {
        let what = what.to_string();
        move |call| IoError::Hdf5Call {
            path: self.h5_path.clone(),
            call,
            what: what.clone(),
        }
    }

    fn h5_err(&self, what: &str) -> impl Fn(hdf5::Error) -> IoError + '_ {
        let what = what.to_string();
        move |e| IoError::hdf5(&self.h5_path, what.clone(), e)
    }

    fn write_static(&mut self, center: Center, name: &str, values: &[i32]) -> Result<(), IoError> {
        let rows = self.rows(center);
        let what = format!("writing static {} field {name:?}", center.group());
        let local = check_name("static field", name)
            .and_then(|()| {
                if self.model.statics.iter().any(|(n, c)| n == name && *c == center) {
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

        let result = (|| {
            let group = &self.static_groups[Self::group_index(center)];
            let ds = fixed_dataset::<i32>(group, name, &[rows.global])
                .map_err(self.h5_err(&format!("creating /static/{}/{name}", center.group())))?;
            ffi::write_block(&ds, &self.xfer, &[rows.offset], &[rows.count], values)
                .map_err(self.call_err(&what))?;
            Ok(())
        })();
        let result = agree(&self.comm, &self.h5_path, &what, result);
        if result.is_err() {
            self.usable = false;
            return result;
        }
        self.model.statics.push((name.to_string(), center));
        self.publish(&what)
    }

    /// Local validation of a step's arguments.
    fn check_step(&self, time: f64, lists: FieldLists<'_, '_>) -> Result<(), String> {
        if !time.is_finite() {
            return Err(format!("time {time} is not finite"));
        }
        if let Some(&last) = self.model.times.last() {
            if time <= last {
                return Err(format!(
                    "time {time:e} is not larger than the previous step's time {last:e}"
                ));
            }
        }
        for (center, list) in lists {
            let rows = self.rows(center).count;
            let kind = center.group();
            for (i, &(name, comps, values)) in list.iter().enumerate() {
                check_name(&format!("{kind} field"), name)?;
                if xdmf::attribute_type(comps).is_none() {
                    return Err(format!(
                        "{kind} field {name:?}: {comps} components (supported: 1, 3, 6, 9)"
                    ));
                }
                if list[..i].iter().any(|f| f.0 == name) {
                    return Err(format!("{kind} field {name:?} is given twice"));
                }
                if values.len() as u64 != rows * comps as u64 {
                    return Err(format!(
                        "{kind} field {name:?} has {} values on rank {}, expected {rows} rows x {comps} = {}",
                        values.len(),
                        self.rank,
                        rows * comps as u64
                    ));
                }
            }
            if let Some(fields) = &self.fields {
                let known: Vec<&FieldDesc> = fields
                    .iter()
                    .map(|f| &f.desc)
                    .filter(|d| d.center == center)
                    .collect();
                for d in &known {
                    match list.iter().find(|f| f.0 == d.name) {
                        None => {
                            return Err(format!(
                                "{kind} field {:?} is missing (the first step fixes the field set)",
                                d.name
                            ))
                        }
                        Some(f) if f.1 != d.components => {
                            return Err(format!(
                                "{kind} field {:?} has {} components, the first step had {}",
                                d.name, f.1, d.components
                            ))
                        }
                        Some(_) => {}
                    }
                }
                if let Some(extra) = list.iter().find(|f| !known.iter().any(|d| d.name == f.0)) {
                    return Err(format!(
                        "{kind} field {:?} was not in the first step (the first step fixes the field set)",
                        extra.0
                    ));
                }
            }
        }
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

        let result = self.write_step_data(step, time, lists);
        let result = agree(&self.comm, &self.h5_path, &what, result);
        if result.is_err() {
            self.usable = false;
            return result;
        }
        self.model.times.push(time);
        self.publish(&what)
    }

    /// Creates the field datasets (first step only) and writes one step. Collective.
    fn write_step_data(
        &mut self,
        step: usize,
        time: f64,
        lists: FieldLists<'_, '_>,
    ) -> Result<(), IoError> {
        if self.fields.is_none() {
            let mut slots = Vec::new();
            for (center, list) in lists {
                for &(name, comps, _) in list {
                    let parent = &self.field_groups[Self::group_index(center)];
                    let what = format!("creating group /fields/{}/{name}", center.group());
                    ffi::create_group_reserving_names(parent, name, STEP_NAMES_RESERVED)
                        .map_err(self.call_err(&what))?;
                    let group = parent.group(name).map_err(self.h5_err(&what))?;
                    slots.push(FieldSlot {
                        desc: FieldDesc {
                            name: name.to_string(),
                            center,
                            components: comps,
                        },
                        group,
                    });
                }
            }
            self.model.fields = slots.iter().map(|s| s.desc.clone()).collect();
            self.fields = Some(slots);
        }
        let fields = self.fields.as_ref().unwrap_or_else(|| unreachable!());
        let step_name = xdmf::step_name(step);
        for slot in fields {
            let d = &slot.desc;
            let what = format!(
                "writing /fields/{}/{}/{step_name}",
                d.center.group(),
                d.name
            );
            let rows = self.rows(d.center);
            let list = lists[Self::group_index(d.center)].1;
            let values = list
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
            let ds = fixed_dataset::<f64>(&slot.group, &step_name, &shape)
                .map_err(self.h5_err(&what))?;
            ffi::write_block(&ds, &self.xfer, &start, &count, values)
                .map_err(self.call_err(&what))?;
        }
        let what = format!("writing /time step {step}");
        self.time_ds.resize(step + 1).map_err(self.h5_err(&what))?;
        let (count, data): (u64, &[f64]) = if self.rank == 0 {
            (1, &[time])
        } else {
            (0, &[])
        };
        ffi::write_block(&self.time_ds, &self.xfer, &[step as u64], &[count], data)
            .map_err(self.call_err(&what))?;
        Ok(())
    }

    /// Makes the current state durable and visible: global flush, barrier, then
    /// rank 0 replaces the XDMF file (only if at least one step exists). Collective.
    fn publish(&mut self, what: &str) -> Result<(), IoError> {
        let flushed =
            ffi::flush_global(&self.file).map_err(self.call_err(&format!("flushing after {what}")));
        let flushed = agree(&self.comm, &self.h5_path, what, flushed);
        if flushed.is_err() {
            self.usable = false;
            return flushed;
        }
        // Every rank's data and metadata are on disk before the index names them.
        self.comm.barrier();
        if !self.model.times.is_empty() {
            self.rename_into_place()?;
        }
        let indexed = if self.rank == 0 && !self.model.times.is_empty() {
            xdmf::write_atomic(&self.xdmf_path, &self.model.render())
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

    /// Collective, after a flush and a barrier: renames `<stem>.h5.part` to
    /// `<stem>.h5` if that is still to be done.
    fn rename_into_place(&mut self) -> Result<(), IoError> {
        let Some(part) = self.pending.take() else {
            return Ok(());
        };
        let renamed = if self.rank == 0 {
            std::fs::rename(&part, &self.h5_path)
                .map_err(|e| IoError::io(&self.h5_path, "renaming the new HDF5 file into place", e))
        } else {
            Ok(())
        };
        let renamed = agree(
            &self.comm,
            &self.h5_path,
            "renaming the new HDF5 file",
            renamed,
        );
        if renamed.is_err() {
            self.usable = false;
        }
        renamed
    }

    /// Final flush, the rename into place if no step did it, mesh-only XDMF
    /// if no step was written, and close. Collective. A file that never
    /// reached its place (an error before) is removed.
    fn finish(mut self) -> Result<(), IoError> {
        let mut result = Ok(());
        if self.usable {
            let flushed = ffi::flush_global(&self.file).map_err(|call| IoError::Hdf5Call {
                path: self.h5_path.clone(),
                call,
                what: "flushing before close".into(),
            });
            result = agree(&self.comm, &self.h5_path, "flushing before close", flushed);
            if result.is_ok() {
                self.comm.barrier();
                result = self.rename_into_place();
            }
            if result.is_ok() && self.model.times.is_empty() {
                let indexed = if self.rank == 0 {
                    xdmf::write_atomic(&self.xdmf_path, &self.model.render())
                } else {
                    Ok(())
                };
                result = agree(
                    &self.comm,
                    &self.xdmf_path,
                    "writing the XDMF file",
                    indexed,
                );
            }
        }
        let Self {
            comm,
            rank,
            h5_path,
            fields,
            time_ds,
            static_groups,
            field_groups,
            file,
            xfer,
            pending,
            ..
        } = self;
        drop((fields, time_ds, static_groups, field_groups, xfer));
        let closed = file
            .close()
            .map_err(|e| IoError::hdf5(&h5_path, "closing the file", e));
        let closed = agree(&comm, &h5_path, "closing the file", closed);
        if let (Some(part), 0) = (pending, rank) {
            let _ = std::fs::remove_file(part);
        }
        result.and(closed)
    }
}

/// `<stem>.h5.part`: the HDF5 file while its mesh is being written.
pub(crate) fn part_path(h5: &Path) -> PathBuf {
    let mut name = h5.as_os_str().to_owned();
    name.push(".part");
    PathBuf::from(name)
}

/// A contiguous, early-allocated dataset of fixed shape. Collective.
fn fixed_dataset<T: H5Type>(group: &Group, name: &str, shape: &[u64]) -> hdf5::Result<Dataset> {
    let shape: Vec<usize> = shape.iter().map(|&d| d as usize).collect();
    group
        .new_dataset::<T>()
        .shape(shape)
        .alloc_time(Some(AllocTime::Early))
        .fill_time(FillTime::Never)
        .create(name)
}
