//! Continuing a series in place after a restart: the mesh file is checked
//! against the run's mesh and kept as it is, the steps up to the checkpoint
//! are kept, the later ones are dropped from the index and then removed.

use std::path::Path;

use hdf5::File;
use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::{Communicator, CommunicatorCollectives};

use super::super::read::read_step_time;
use super::super::xdmf::{Center, FieldDesc, XdmfModel};
use super::super::{output_paths, step_path, steps_dir, IoError};
use super::checks::{agree, agree_signature, Fnv};
use super::files::remove_steps_from;
use super::{CollectiveXfer, Inner, MeshPart, Rows, TimeSeriesWriter};

/// The static fields of a mesh file: name and center.
type Statics = Vec<(String, Center)>;

/// What a rank finds in the files of the series.
struct Found {
    /// Static fields of the mesh file.
    statics: Vec<(String, Center)>,
    /// Times of the steps kept (those up to the checkpoint).
    times: Vec<f64>,
    /// The fields of the first step, if one is kept.
    fields: Option<Vec<FieldDesc>>,
}

impl TimeSeriesWriter {
    /// Collective. Reopens the series `<dir>/<stem>` of an earlier run to
    /// continue it (a restart in place): keeps the steps with times up to
    /// `keep_until` (the checkpoint's time), removes the later ones and
    /// returns a writer that appends after them. The mesh file must hold the
    /// same mesh in the same row order (`mesh` and this rank's original node
    /// ids `node_ids` are compared with the file's rows): a series written
    /// with another partition, for example on another number of ranks, is an
    /// error saying so. The mesh file and its static fields are kept as they
    /// are; the XDMF file is rewritten to list the kept steps before any later
    /// step file is removed.
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
        // Every rank reads the files (serial driver, read-only) and checks its rows.
        let check = check_mesh_file(&h5_path, mesh, node_ids, nodes, cells);
        let check = agree(&comm, &h5_path, "checking the series to continue", check)?;
        let mismatch = i32::from(check.is_err());
        let mut any = 0;
        comm.all_reduce_into(&mismatch, &mut any, SystemOperation::max());
        let (statics, with_hexes) = match check {
            Ok(found) if any == 0 => found,
            other => {
                return Err(IoError::invalid(
                    &h5_path,
                    format!(
                        "cannot continue this series in place: {}; restart into another \
                         output directory (--output), or on the rank count that wrote it",
                        other
                            .err()
                            .unwrap_or_else(|| "another rank's rows differ".into())
                    ),
                ))
            }
        };
        let found = kept_steps(&h5_path, keep_until).map(|(times, fields)| Found {
            statics,
            times,
            fields,
        });
        // The same view on every rank: step times and fields.
        let sig = found.as_ref().map_or(0, |f| {
            let mut sig = Fnv::new().u64(f.times.len() as u64);
            for t in &f.times {
                sig = sig.u64(t.to_bits());
            }
            for d in f.fields.iter().flatten() {
                sig = sig.str(&d.name).u64(d.components as u64);
            }
            sig.0
        });
        let (local, found) = match found {
            Ok(f) => (Ok(()), Some(f)),
            Err(e) => (Err(e), None),
        };
        agree_signature(&comm, &h5_path, "reading the steps", local, sig)?;
        let found = found.unwrap_or_else(|| unreachable!("agreed on success"));

        let xfer = CollectiveXfer::new().map_err(|call| IoError::Hdf5Call {
            path: h5_path.clone(),
            call,
            what: "creating a transfer property list".into(),
        });
        let xfer = agree(&comm, &h5_path, "continuing the series", xfer)?;
        let mut model = XdmfModel {
            h5_name: format!("{stem}.h5"),
            steps_name: steps_dir(&h5_path)
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned(),
            nodes: nodes.global,
            cells: cells.global,
            nodes_per_cell: mesh.nodes_per_cell,
            statics: found.statics,
            fields: found.fields.clone().unwrap_or_default(),
            times: found.times,
            hexes: 0,
            hex_blocks: Vec::new(),
        };
        if let Some(h) = mesh.hexes.as_ref().filter(|_| with_hexes) {
            model.hexes = h.global;
            model.hex_blocks = h.blocks.to_vec();
        }
        model.sort();
        let inner =
            Inner {
                rank,
                xdmf_path,
                nodes,
                cells,
                xfer,
                mesh: None,
                fields: found.fields.map(|_| model.fields.clone()),
                hexes: mesh.hexes.as_ref().filter(|_| with_hexes).map(|h| {
                    super::hexes::Sample::new(h.global, h.blocks, cells.offset, cells.count)
                }),
                model,
                usable: true,
                h5_path,
                comm,
            };
        // The index first, so that it never names a removed step.
        inner.write_index()?;
        let kept = inner.model.times.len();
        let removed = if rank == 0 {
            remove_steps_from(&inner.h5_path, kept)
        } else {
            Ok(())
        };
        agree(
            &inner.comm,
            &inner.h5_path,
            "removing the steps after the checkpoint",
            removed,
        )?;
        Ok(Self { inner: Some(inner) })
    }
}

/// Checks that the mesh file `h5` holds this run's mesh in this rank's rows;
/// returns its static fields and whether it has this run's hexes (it has
/// none if written before the hexahedral index), or what differs as `Err`. An I/O error is the
/// outer error.
fn check_mesh_file(
    h5: &Path,
    mesh: &MeshPart,
    node_ids: &[i32],
    nodes: Rows,
    cells: Rows,
) -> Result<Result<(Statics, bool), String>, IoError> {
    let h5err = |what: &str| {
        let what = what.to_string();
        move |e| IoError::hdf5(h5, what, e)
    };
    let file = File::open(h5).map_err(h5err("opening the series to continue it"))?;
    if file.link_exists("time") || file.link_exists("fields") {
        return Ok(Err(
            "it was written by an older fdem, with all steps in one file".into(),
        ));
    }
    let coords = file
        .dataset("mesh/coordinates")
        .map_err(h5err("opening /mesh/coordinates"))?;
    let topo = file
        .dataset("mesh/topology")
        .map_err(h5err("opening /mesh/topology"))?;
    if coords.shape() != [nodes.global as usize, 3]
        || topo.shape() != [cells.global as usize, mesh.nodes_per_cell]
    {
        return Ok(Err(format!(
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
            d.read_slice_1d::<i32, _>(nodes.offset as usize..(nodes.offset + nodes.count) as usize)
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
        return Ok(Err(
            "its rows are in another order (another partition, or another number of ranks)".into(),
        ));
    }
    let mut statics = Vec::new();
    for center in [Center::Node, Center::Cell] {
        let name = format!("static/{}", center.group());
        let group = file
            .group(&name)
            .map_err(h5err(&format!("opening /{name}")))?;
        for field in group
            .member_names()
            .map_err(h5err(&format!("listing /{name}")))?
        {
            statics.push((field, center));
        }
    }
    let with_hexes = match &mesh.hexes {
        Some(h) => match super::hexes::in_file(&file, h5, h)? {
            Ok(found) => found,
            Err(what) => return Ok(Err(what)),
        },
        None => false,
    };
    Ok(Ok((statics, with_hexes)))
}

/// The steps of the series of mesh file `h5` with times up to `keep_until`
/// (to 1e-9 relative): their times, and the fields of the first one.
fn kept_steps(h5: &Path, keep_until: f64) -> Result<(Vec<f64>, Option<Vec<FieldDesc>>), IoError> {
    let tol = 1e-9 * keep_until.abs().max(1.0);
    let mut times = Vec::new();
    loop {
        let path = step_path(h5, times.len());
        if !path.is_file() {
            break;
        }
        let t = read_step_time(&path)?;
        if t > keep_until + tol {
            break;
        }
        times.push(t);
    }
    if times.is_empty() {
        return Ok((times, None));
    }
    let first = step_path(h5, 0);
    let first = first.as_path();
    let h5err = |what: String| move |e| IoError::hdf5(first, what, e);
    let file = File::open(first).map_err(h5err("opening the first step".into()))?;
    let mut fields = Vec::new();
    for center in [Center::Node, Center::Cell] {
        let name = format!("fields/{}", center.group());
        let group = file
            .group(&name)
            .map_err(h5err(format!("opening /{name}")))?;
        for field in group
            .member_names()
            .map_err(h5err(format!("listing /{name}")))?
        {
            let shape = group
                .dataset(&field)
                .map_err(h5err(format!("opening /{name}/{field}")))?
                .shape();
            fields.push(FieldDesc {
                name: field,
                center,
                components: if shape.len() == 1 { 1 } else { shape[1] },
            });
        }
    }
    Ok((times, Some(fields)))
}
