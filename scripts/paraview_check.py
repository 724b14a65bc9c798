# ParaView as the real client of fdem's output: run by scripts/paraview-check.sh
# under `xvfb-run -a pvbatch scripts/paraview_check.py OUT_DIR/STEM.xdmf ...`.
#
# For every XDMF file given, opens it with the Xdmf3 reader (Xdmf3ReaderS)
# and the legacy reader (XDMFReader) and checks, against the HDF5 files (the
# mesh file STEM.h5 and the step files STEM_steps/NNNNNN.h5) read
# independently of fdem and of ParaView (raw values exported by h5dump):
#   - the point and cell array names (the fields and static fields the file
#     holds), the numbers of points and cells;
#   - the number and values of the time steps;
#   - at every step, every array's values, the temperature range, and the
#     six stress components: the XDMF Tensor6 order is xx, xy, xz, yy, yz,
#     zz, so a reader that expands the tensor to 9 components must show
#     T[i][j] = row[k(i, j)] with that order;
#   - both readers agree with each other.
# Physical check of the stress as ParaView shows it (hot block on a floor):
# the volume mean of the resting block's stress is the weight's, sigma_zz =
# -rho g h / 2, with the other five components small (the thermal stresses
# average out); with the old xx, yy, zz, xy, yz, xz rows ParaView would show
# that mean in XZ instead.
# A hexahedral index STEM_hex8.xdmf (Hex8 bodies, issue 21) is checked on
# its own: one block of VTK hexahedra per Hex8 body, the corners of
# /mesh/hexes, positive volumes summing to the body's tets' volume, every
# point field as in the step files, and every cell field and static cell
# field (from /fields/hex, /static/hex) that of the hex's first tet, in
# both readers.
# Saves a PNG of the temperature at the last step next to each XDMF file
# (displacement magnitude for a purely mechanical run) and prints its path.
import os
import subprocess
import sys
import tempfile

import numpy as np
from paraview import servermanager
from paraview.simple import (
    Clip,
    ColorBy,
    CreateView,
    Delete,
    GetColorTransferFunction,
    ResetSession,
    SaveScreenshot,
    Show,
    WarpByVector,
    XDMFReader,
    Xdmf3ReaderS,
)
from vtkmodules.util.numpy_support import vtk_to_numpy

# XDMF Tensor6: (row, column) of each of the six stored components.
TENSOR6 = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]

failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("  FAIL: " + what)
    return ok


# ---------------------------------------------------------------- HDF5 side
def h5_objects(h5):
    """Dataset paths of the file, from `h5dump -n`."""
    out = subprocess.run(
        ["h5dump", "-n", h5], check=True, capture_output=True, text=True
    ).stdout
    return [
        line.split()[1]
        for line in out.splitlines()
        if line.strip().startswith("dataset ")
    ]


def h5_read(h5, dataset, dtype):
    """Raw values of one dataset, exported by `h5dump -b LE`."""
    with tempfile.NamedTemporaryFile(suffix=".bin") as tmp:
        subprocess.run(
            ["h5dump", "-d", dataset, "-b", "LE", "-o", tmp.name, h5],
            check=True,
            capture_output=True,
        )
        return np.fromfile(tmp.name, dtype=dtype)


class H5:
    """A series: the mesh file `<stem>.h5` and its step files
    `<stem>_steps/000000.h5`, ... (present from 000000 on)."""

    def __init__(self, path):
        self.path = path
        steps_dir = os.path.splitext(path)[0] + "_steps"
        self.steps = []
        while os.path.isfile(os.path.join(steps_dir, "%06d.h5" % len(self.steps))):
            self.steps.append(os.path.join(steps_dir, "%06d.h5" % len(self.steps)))
        self.times = np.array(
            [h5_read(f, "/time", "<f8")[0] for f in self.steps], dtype=float
        )
        self.coords = h5_read(path, "/mesh/coordinates", "<f8").reshape(-1, 3)
        self.topology = h5_read(path, "/mesh/topology", "<u4").reshape(-1, 4)
        self.nodes, self.cells = len(self.coords), len(self.topology)
        # {center: {name: [file per step]}}
        # "hex": the hexes' rows of the cell fields (series with Hex8 bodies).
        self.fields = {"node": {}, "cell": {}, "hex": {}}
        self.statics = {"node": [], "cell": [], "hex": []}
        for o in h5_objects(path):
            parts = o.strip("/").split("/")
            if parts[0] == "static" and len(parts) == 3:
                self.statics[parts[1]].append(parts[2])
        for f in self.steps:
            for o in h5_objects(f):
                parts = o.strip("/").split("/")
                if parts[0] == "fields" and len(parts) == 3:
                    self.fields[parts[1]].setdefault(parts[2], []).append(f)

    def rows(self, center):
        return self.nodes if center == "node" else self.cells

    def field(self, center, name, k):
        v = h5_read(
            self.fields[center][name][k], "/fields/%s/%s" % (center, name), "<f8"
        )
        rows = self.rows(center)
        return v.reshape(rows, -1) if v.size != rows else v

    def static(self, center, name):
        return h5_read(self.path, "/static/%s/%s" % (center, name), "<i4")


def tensor9(rows6):
    """Full 3x3 tensors (row-major, 9 values) from XDMF Tensor6 rows."""
    out = np.empty((len(rows6), 3, 3))
    for k, (i, j) in enumerate(TENSOR6):
        out[:, i, j] = rows6[:, k]
        out[:, j, i] = rows6[:, k]
    return out.reshape(-1, 9)


# ----------------------------------------------------------- ParaView side
READERS = {
    "Xdmf3ReaderS": lambda f: Xdmf3ReaderS(FileName=[f]),
    "XDMFReader": lambda f: XDMFReader(FileNames=[f]),
}


def as_grid(data):
    """The unstructured grid of a reader's output (the legacy reader may wrap it)."""
    if data.IsA("vtkMultiBlockDataSet"):
        it = data.NewIterator()
        it.InitTraversal()
        return it.GetCurrentDataObject()
    return data


def arrays(attrs):
    """Copies of the arrays: the reader reuses its output on the next update."""
    return {
        attrs.GetArrayName(i): np.array(vtk_to_numpy(attrs.GetArray(i)))
        for i in range(attrs.GetNumberOfArrays())
    }


def read_all(reader_name, xdmf, h5):
    """{step: {center: {name: values}}}, after checking names and times."""
    print("  %s:" % reader_name)
    reader = READERS[reader_name](xdmf)
    reader.UpdatePipelineInformation()
    times = np.array(reader.TimestepValues, dtype=float).ravel()
    if len(h5.times) == 1 and times.size == 0:
        times = h5.times.copy()
    check(
        len(times) == len(h5.times),
        "%s %s: %d time steps, the HDF5 file has %d"
        % (reader_name, xdmf, len(times), len(h5.times)),
    )
    check(
        len(times) == len(h5.times)
        and np.allclose(times, h5.times, rtol=1e-14, atol=0.0),
        "%s %s: time values %s differ from the step files' /time %s"
        % (reader_name, xdmf, times[:5], h5.times[:5]),
    )
    print("    %d time steps, t = %g .. %g" % (len(times), times[0], times[-1]))
    steps = []
    for k, t in enumerate(h5.times):
        reader.UpdatePipeline(t)
        grid = as_grid(servermanager.Fetch(reader))
        check(
            grid.GetNumberOfPoints() == h5.nodes
            and grid.GetNumberOfCells() == h5.cells,
            "%s step %d: %d points, %d cells; the HDF5 file has %d, %d"
            % (
                reader_name,
                k,
                grid.GetNumberOfPoints(),
                grid.GetNumberOfCells(),
                h5.nodes,
                h5.cells,
            ),
        )
        steps.append(
            {"node": arrays(grid.GetPointData()), "cell": arrays(grid.GetCellData())}
        )
    for center, label in (("node", "point"), ("cell", "cell")):
        want = sorted(list(h5.fields[center]) + h5.statics[center])
        got = sorted(steps[-1][center])
        check(
            got == want,
            "%s: %s arrays %s, the HDF5 file has %s" % (reader_name, label, got, want),
        )
        print("    %s arrays: %s" % (label, ", ".join(got)))
    Delete(reader)
    return steps


def compare_step(reader_name, h5, k, step, stress_components):
    for center in ("node", "cell"):
        for name in h5.statics[center]:
            want = h5.static(center, name)
            got = step[center].get(name)
            check(
                got is not None and np.array_equal(np.ravel(got), want),
                "%s step %d: static %s field %s differs from the HDF5 file"
                % (reader_name, k, center, name),
            )
        for name in h5.fields[center]:
            want = h5.field(center, name, k)
            got = step[center].get(name)
            if got is None:
                check(False, "%s step %d: no array %s" % (reader_name, k, name))
                continue
            got = np.asarray(got, dtype=float)
            if name == "stress" or (want.ndim == 2 and want.shape[1] == 6):
                ncomp = got.shape[1] if got.ndim == 2 else 1
                stress_components.add(ncomp)
                if ncomp == 9:
                    want = tensor9(want)
                elif ncomp != 6:
                    check(
                        False,
                        "%s step %d: %s has %d components"
                        % (reader_name, k, name, ncomp),
                    )
                    continue
            check(
                got.shape == want.shape and np.array_equal(got, want),
                "%s step %d: %s %s differs from the HDF5 file (max |diff| %s)"
                % (
                    reader_name,
                    k,
                    center,
                    name,
                    np.max(np.abs(got - want)) if got.shape == want.shape else "shape",
                ),
            )
            if name == "temperature":
                check(
                    (got.min(), got.max()) == (want.min(), want.max()),
                    "%s step %d: temperature range (%g, %g), HDF5 (%g, %g)"
                    % (reader_name, k, got.min(), got.max(), want.min(), want.max()),
                )


def tet_volumes(coords, topo):
    p = coords[topo]
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    return np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0


def resting_block_check(reader_name, h5, steps, body, density, gravity, height):
    """Volume mean of the stress ParaView shows in a resting block."""
    grid = steps[-1]
    stress = np.asarray(grid["cell"]["stress"], dtype=float)
    full = stress.reshape(-1, 3, 3) if stress.shape[1] == 9 else tensor9(stress).reshape(-1, 3, 3)
    in_body = np.asarray(grid["cell"]["body"]).ravel() == body
    vol = tet_volumes(h5.coords, h5.topology)[in_body]
    mean = np.einsum("i,ijk->jk", vol, full[in_body]) / vol.sum()
    weight = -density * gravity * height / 2.0
    names = ["XX", "XY", "XZ", "YY", "YZ", "ZZ"]
    shown = ", ".join(
        "%s %.1f" % (n, mean[i, j]) for n, (i, j) in zip(names, TENSOR6)
    )
    print("    mean stress of the block as shown (Pa): %s; weight: ZZ = %.1f" % (shown, weight))
    check(
        abs(mean[2, 2] / weight - 1.0) < 0.3,
        "%s: the block's mean ZZ stress %.1f Pa is not the weight's %.1f Pa"
        % (reader_name, mean[2, 2], weight),
    )
    for n, (i, j) in zip(names, TENSOR6):
        if (i, j) != (2, 2):
            check(
                abs(mean[i, j]) < 0.2 * abs(weight),
                "%s: the block's mean %s stress %.1f Pa is not small against the weight's %.1f Pa"
                % (reader_name, n, mean[i, j], weight),
            )


def screenshot(xdmf, h5):
    png = os.path.splitext(xdmf)[0] + "_last.png"
    reader = Xdmf3ReaderS(FileName=[xdmf])
    reader.UpdatePipelineInformation()
    view = CreateView("RenderView")
    view.ViewSize = [800, 600]
    view.ViewTime = float(h5.times[-1])
    view.OrientationAxesVisibility = 0
    # As a user looks at it: the deformed shape (Warp By Vector on the
    # displacement), cut in half through the middle (whole cells, the near
    # half removed) so that a container does not hide its particles.
    shown = reader
    if "displacement" in h5.fields["node"]:
        shown = WarpByVector(Input=shown, Vectors=["POINTS", "displacement"])
    shown.UpdatePipeline(float(h5.times[-1]))
    b = shown.GetDataInformation().GetBounds()
    clip = Clip(Input=shown, ClipType="Plane", Crinkleclip=1)
    clip.ClipType.Origin = [0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5])]
    clip.ClipType.Normal = [0.0, -1.0, 0.0]
    clip.Invert = 1
    display = Show(clip, view)
    if "temperature" in h5.fields["node"]:
        array, what = "temperature", "temperature"
    else:
        array, what = "displacement", "displacement magnitude"
    ColorBy(display, ("POINTS", array))
    display.RescaleTransferFunctionToDataRange(False, True)
    display.SetScalarBarVisibility(view, True)
    GetColorTransferFunction(array)
    view.CameraPosition = [1.0, -2.0, 1.2]
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.ResetCamera()
    SaveScreenshot(png, view, ImageResolution=[800, 600])
    Delete(display)
    Delete(view)
    Delete(clip)
    if shown is not reader:
        Delete(shown)
    Delete(reader)
    print("  PNG (%s at t = %g, near half cut away): %s" % (what, h5.times[-1], png))


def hex_volumes(pts):
    """Volumes of hexahedra (VTK order) as six tets around the 0-6 diagonal."""
    tets = [(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)]
    vol = np.zeros(len(pts))
    for t in tets:
        p = pts[:, list(t)]
        a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
        vol += np.einsum("ij,ij->i", np.cross(a, b), c) / 6.0
    return vol


def hex8_check(xdmf):
    """The hexahedral index of a series against its HDF5 files."""
    h5 = H5(xdmf[: -len("_hex8.xdmf")] + ".h5")
    hexes = h5_read(h5.path, "/mesh/hexes", "<u4").reshape(-1, 8)
    # The Hex8 bodies' tets: those with all four nodes among the hexes'.
    in_hex = np.zeros(h5.nodes, dtype=bool)
    in_hex[hexes.ravel()] = True
    hex_tets = np.flatnonzero(in_hex[h5.topology].all(axis=1))
    # Hexes and their tets body after body: hex i is hex_tets[6 i .. 6 i + 6].
    first = hex_tets[::6]
    print("  HDF5: %d hexes over %d tets, %d steps" % (len(hexes), h5.cells, len(h5.times)))
    for name in READERS:
        reader = READERS[name](xdmf)
        reader.UpdatePipelineInformation()
        times = np.array(reader.TimestepValues, dtype=float).ravel()
        check(
            len(times) == len(h5.times) and np.allclose(times, h5.times, rtol=1e-14, atol=0),
            "%s %s: times %s, the step files %s" % (name, xdmf, times[:3], h5.times[:3]),
        )
        k = len(h5.times) - 1
        reader.UpdatePipeline(h5.times[-1])
        g = as_grid(servermanager.Fetch(reader))
        n = g.GetNumberOfCells()
        check(n == len(hexes), "%s: %d hexes shown, %d written" % (name, n, len(hexes)))
        conn = np.array([[g.GetCell(c).GetPointId(i) for i in range(8)] for c in range(n)])
        types = {g.GetCellType(c) for c in range(n)}
        check(types == {12}, "%s: cell types %s, not VTK_HEXAHEDRON (12)" % (name, types))
        check(np.array_equal(conn, hexes), "%s: hex corners differ from /mesh/hexes" % name)
        vol = hex_volumes(h5.coords[hexes])
        tets = tet_volumes(h5.coords, h5.topology[hex_tets]).sum()
        check(
            vol.min() > 0 and abs(vol.sum() / tets - 1) < 1e-12,
            "%s: hex volumes (min %g, sum %g) against the tets' %g" % (name, vol.min(), vol.sum(), tets),
        )
        cell = arrays(g.GetCellData())
        point = arrays(g.GetPointData())
        check(
            sorted(cell) == sorted(list(h5.fields["cell"]) + h5.statics["cell"]),
            "%s: cell fields %s of the hexes, the tets have %s"
            % (name, sorted(cell), sorted(list(h5.fields["cell"]) + h5.statics["cell"])),
        )
        for f in h5.statics["cell"]:
            want = h5.static("cell", f)[first]
            got = np.asarray(cell.get(f, []), dtype=float)
            check(np.array_equal(got, want), "%s: static cell field %s of the hexes" % (name, f))
        for f in h5.fields["cell"]:
            want = h5.field("cell", f, k)[first]
            got = np.asarray(cell.get(f, []), dtype=float)
            if want.ndim == 2 and want.shape[1] == 6 and got.ndim == 2 and got.shape[1] == 9:
                want = tensor9(want)
            check(np.array_equal(got, want), "%s: cell field %s of the hexes" % (name, f))
        for f in h5.fields["node"]:
            want = h5.field("node", f, k)
            got = np.asarray(point.get(f, []), dtype=float)
            check(np.array_equal(got, want), "%s: point field %s" % (name, f))
        shown = sorted(set(h5.fields["cell"]) & set(cell))
        print(
            "  %s: %d hexahedra (volume %.6g), point fields as written, cell fields %s "
            "as their first tets'" % (name, n, vol.sum(), shown)
        )
        Delete(reader)
    ResetSession()


def main(args):
    block = None
    files = []
    for a in args:
        if a.startswith("--resting-block="):
            # body id, density, gravity, height of a block resting on a floor
            block = [float(x) for x in a.split("=", 1)[1].split(",")]
        else:
            files.append((a, block))
            block = None
    for xdmf, block in files:
        print("%s:" % xdmf)
        if xdmf.endswith("_hex8.xdmf"):
            hex8_check(xdmf)
            continue
        h5 = H5(os.path.splitext(xdmf)[0] + ".h5")
        print(
            "  HDF5 (h5dump): %d nodes, %d cells, %d steps; fields node %s, cell %s"
            % (
                h5.nodes,
                h5.cells,
                len(h5.times),
                sorted(h5.fields["node"]),
                sorted(h5.fields["cell"]),
            )
        )
        for center, f in h5.fields.items():
            for name, steps in f.items():
                check(
                    len(steps) == len(h5.times),
                    "%s: %d datasets of %s field %s for %d times"
                    % (xdmf, len(steps), center, name, len(h5.times)),
                )
        per_reader = {}
        for name in READERS:
            steps = read_all(name, xdmf, h5)
            components = set()
            before = len(failures)
            for k, step in enumerate(steps):
                compare_step(name, h5, k, step, components)
            if components:
                print(
                    "    stress: %s components per cell, equal to the HDF5 rows in XDMF "
                    "Tensor6 order (xx, xy, xz, yy, yz, zz)" % sorted(components)
                    if len(failures) == before
                    else "    stress: %s components per cell" % sorted(components)
                )
            if "temperature" in h5.fields["node"]:
                t = np.asarray(steps[-1]["node"]["temperature"])
                print("    temperature range at the last step: %.6g .. %.6g" % (t.min(), t.max()))
            if block is not None:
                resting_block_check(name, h5, steps, int(block[0]), *block[1:])
            per_reader[name] = steps
        a, b = per_reader.values()
        before = len(failures)
        for k in range(min(len(a), len(b))):
            for center in ("node", "cell"):
                for name in a[k][center]:
                    x = np.asarray(a[k][center][name], dtype=float)
                    y = np.asarray(b[k][center].get(name, []), dtype=float)
                    if x.ndim == 2 and y.ndim == 2 and x.shape[1] == 6 and y.shape[1] == 9:
                        x = tensor9(x)
                    if y.ndim == 2 and x.ndim == 2 and y.shape[1] == 6 and x.shape[1] == 9:
                        y = tensor9(y)
                    check(
                        x.shape == y.shape and np.array_equal(x, y),
                        "step %d: the readers disagree on %s field %s" % (k, center, name),
                    )
        if len(failures) == before:
            print("  the two readers agree on every array at every step")
        screenshot(xdmf, h5)
        ResetSession()
    if failures:
        print("paraview-check: %d failure(s)" % len(failures))
        sys.exit(1)
    print("paraview-check: all checks passed (%d files)" % len(files))


main(sys.argv[1:])
