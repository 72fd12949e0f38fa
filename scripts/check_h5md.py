#!/usr/bin/python3
"""Check the layout of an H5MD trajectory (as written by granagg's H5mdWriter) with h5py.

Usage:  /usr/bin/python3 scripts/check_h5md.py traj.h5 [--group all] [--quiet]

Checks the H5MD 1.1 structure (docs/ARCHITECTURE.md): /h5md version, author and creator; the
particle group (by default the first under /particles, as MDAnalysis picks it) with position,
box (dimension 3, periodic boundary, edges per frame), and the optional velocity, charge and image
time series, all with consistent shapes [frames, N, ...]; positions finite and wrapped into
[0, L); a /parameters group. It also replays the steps MDAnalysis 2.x's H5MD reader takes (box
dimension attribute, 3x3 edges per frame, /observables indexed by frame) and, if MDAnalysis is
importable, opens the file with it (convert_units=False: granagg writes reduced units, no `unit`
attributes).

The XDMF sidecar (traj.xdmf next to traj.h5), if present, is checked against the file; with
--paraview it is also loaded with ParaView's (legacy, Xdmf2) "XDMF Reader" and the last frame's
positions compared with the HDF5 data.

Prints N, the number of frames and the box edge; exits 1 listing the problems found, 2 if the
file cannot be opened.
"""
import argparse
import sys

try:
    import h5py
    import numpy as np
except ImportError as exc:  # pragma: no cover
    sys.exit(f"check_h5md.py needs h5py and numpy ({exc}); use /usr/bin/python3 on Debian")


def as_str(x):
    """h5py gives bytes for fixed-length strings and str for variable-length ones."""
    if isinstance(x, (bytes, np.bytes_)):
        return x.decode("utf-8", "replace").rstrip("\0 ")
    return str(x)


class Checker:
    def __init__(self):
        self.problems = []
        self.warnings = []

    def fail(self, msg):
        self.problems.append(msg)

    def warn(self, msg):
        self.warnings.append(msg)

    def series(self, grp, name, inner, required=False):
        ("""Checks a time-dependent element {value, step, time}; """
         """returns (value, step, time) or None.""")
        path = f"{grp.name}/{name}"
        if name not in grp:
            if required:
                self.fail(f"missing {path}")
            return None
        g = grp[name]
        if not isinstance(g, h5py.Group):
            self.fail(f"{path} should be a time-dependent group {{value, step, time}}")
            return None
        for ds in ("value", "step", "time"):
            if ds not in g:
                self.fail(f"missing {path}/{ds}")
                return None
        value, step, time = g["value"], g["step"], g["time"]
        if value.ndim != 1 + len(inner) or tuple(value.shape[1:]) != tuple(inner):
            self.fail(f"{path}/value has shape {value.shape}, "
                      f"expected (frames, {', '.join(map(str, inner))})")
        if step.ndim == 1 and not np.issubdtype(step.dtype, np.integer):
            self.fail(f"{path}/step has type {step.dtype}, expected an integer type")
        if step.ndim == 1 and step.shape[0] < value.shape[0] - 1:
            self.fail(f"{path}/step has {step.shape[0]} entries for {value.shape[0]} values")
        if time.ndim == 1 and time.shape[0] < value.shape[0] - 1:
            self.fail(f"{path}/time has {time.shape[0]} entries for {value.shape[0]} values")
        if "unit" in value.attrs:
            self.warn(f"{path}/value has a unit attribute ({as_str(value.attrs['unit'])}); "
                      "granagg writes reduced units")
        return value, step, time


def check(path, group_name=None, verbose=True, paraview=False):
    c = Checker()
    try:
        f = h5py.File(path, "r")
    except OSError as exc:
        print(f"{path}: cannot open as HDF5 ({exc})", file=sys.stderr)
        return 2
    with f:
        # /h5md metadata
        if "h5md" not in f:
            c.fail("missing /h5md group")
        else:
            h = f["h5md"]
            version = h.attrs.get("version")
            if version is None:
                c.fail("/h5md has no version attribute")
            elif list(np.asarray(version).ravel()) != [1, 1]:
                c.fail(f"/h5md version is {list(np.asarray(version).ravel())}, expected [1, 1]")
            elif not np.issubdtype(np.asarray(version).dtype, np.integer):
                c.fail("/h5md version must be integers")
            for sub, attrs in (("author", ("name",)), ("creator", ("name", "version"))):
                if sub not in h:
                    c.fail(f"missing /h5md/{sub}")
                    continue
                for a in attrs:
                    if a not in h[sub].attrs:
                        c.fail(f"/h5md/{sub} has no {a} attribute")

        # particle group: the first one, as MDAnalysis takes it
        if "particles" not in f or len(f["particles"]) == 0:
            c.fail("missing /particles or no particle group in it")
            return report(c, path, None, None, None, verbose)
        groups = list(f["particles"])
        name = group_name or groups[0]
        if name not in f["particles"]:
            c.fail(f"no particle group /particles/{name} (have {groups})")
            return report(c, path, None, None, None, verbose)
        if group_name and groups[0] != group_name:
            c.warn(f"MDAnalysis reads /particles/{groups[0]}, not /particles/{group_name}")
        p = f["particles"][name]

        # N is not known before reading position: check its rank first
        if "position" not in p or "value" not in p["position"]:
            c.fail(f"missing {p.name}/position/value")
            return report(c, path, None, None, None, verbose)
        pv = p["position"]["value"]
        if pv.ndim != 3 or pv.shape[2] != 3:
            c.fail(f"{pv.name} has shape {pv.shape}, expected (frames, N, 3)")
            return report(c, path, None, None, None, verbose)
        n = pv.shape[1]
        pos = c.series(p, "position", (n, 3), required=True)
        frames = pv.shape[0]
        if pos is not None:
            _, step, time = pos
            if step.ndim == 1:
                frames = min(frames, step.shape[0])
                s = step[:frames]
                if frames > 1 and np.any(np.diff(s) <= 0):
                    c.fail(f"{step.name} is not strictly increasing")
            if time.ndim == 1:
                frames = min(frames, time.shape[0])
        vel = c.series(p, "velocity", (n, 3))
        chg = c.series(p, "charge", (n,))
        img = c.series(p, "image", (n, 3))
        for elem in (vel, chg, img):
            if elem is not None and elem[0].shape[0] < frames:
                c.fail(f"{elem[0].name} has {elem[0].shape[0]} frames, position has {frames}")
        if img is not None and not np.issubdtype(img[0].dtype, np.integer):
            c.fail(f"{img[0].name} has type {img[0].dtype}, expected integers")
        if img is None:
            c.warn("no image counts: unwrapped trajectories cannot be reconstructed")

        # box
        box_L = None
        if "box" not in p:
            c.fail(f"missing {p.name}/box")
        else:
            b = p["box"]
            dim = b.attrs.get("dimension")
            if dim is None or int(np.asarray(dim).ravel()[0]) != 3:
                c.fail(f"{b.name} dimension attribute is {dim}, "
                       "expected 3 (MDAnalysis refuses anything else)")
            bnd = b.attrs.get("boundary")
            if bnd is None:
                c.fail(f"{b.name} has no boundary attribute")
            else:
                bnd = [as_str(x) for x in np.asarray(bnd).ravel()]
                if bnd != ["periodic"] * 3:
                    c.fail(f"{b.name} boundary is {bnd}, expected ['periodic'] * 3")
            if "edges" not in b:
                c.fail(f"missing {b.name}/edges")
            elif isinstance(b["edges"], h5py.Group):
                e = c.series(b, "edges", (3, 3))
                if e is not None:
                    ev = e[0]
                    if ev.shape[0] < frames:
                        c.fail(f"{ev.name} has {ev.shape[0]} frames, position has {frames}")
                    if frames > 0 and ev.shape[1:] == (3, 3):
                        m = ev[:frames]
                        diag = np.stack([m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]], axis=1)
                        off = m.copy()
                        for k in range(3):
                            off[:, k, k] = 0
                        if np.any(off != 0):
                            c.fail(f"{ev.name} has off-diagonal entries (granagg boxes are cubic)")
                        if np.any(diag <= 0) or not np.all(np.isfinite(diag)):
                            c.fail(f"{ev.name} has non-positive or non-finite edges")
                        box_L = diag[:, 0]
            else:
                c.warn(f"{b.name}/edges is a fixed dataset; "
                       "MDAnalysis' H5MD reader expects a 3x3 matrix per frame")
                box_L = np.full(frames, float(np.asarray(b["edges"]).ravel()[0]))

        # positions finite and wrapped into [0, L)
        if box_L is not None and frames > 0:
            for k in range(frames):
                x = pv[k]
                if not np.all(np.isfinite(x)):
                    c.fail(f"frame {k}: non-finite positions")
                    break
                if np.any(x < 0) or np.any(x >= box_L[k]):
                    c.fail(f"frame {k}: positions outside [0, L) with L = {box_L[k]}")
                    break

        if "parameters" not in f:
            c.warn("no /parameters group: the file does not say how it was made")

        # MDAnalysis replays /observables/<name>/value[frame] for every frame
        if "observables" in f:
            for key, g in f["observables"].items():
                if not isinstance(g, h5py.Group) or "value" not in g:
                    c.fail(f"/observables/{key} is not a time series group; "
                           "MDAnalysis would fail on it")
                elif g["value"].shape[0] != frames:
                    c.fail(f"/observables/{key} has {g['value'].shape[0]} samples "
                           f"for {frames} frames; MDAnalysis indexes it by frame")
        if "granagg" in f and "observables" in f["granagg"]:
            for key, g in f["granagg"]["observables"].items():
                if not isinstance(g, h5py.Group) or any(
                        d not in g for d in ("value", "step", "time")):
                    c.fail(f"/granagg/observables/{key} is not a {{value, step, time}} group")
                elif not (g["value"].shape[0] <= g["step"].shape[0] + 1 and g["value"].ndim == 1):
                    c.fail(f"/granagg/observables/{key} has inconsistent lengths")

    mdanalysis_check(c, path, n, frames)
    check_xdmf(c, path, n, frames, paraview)
    return report(c, path, n, frames, box_L, verbose)


def xdmf_path_for(path):
    """Sidecar name as H5mdWriter::xdmfPathFor makes it."""
    for ext in (".h5", ".hdf5", ".h5md", ".hdf"):
        if path.endswith(ext) and len(path) > len(ext):
            return path[: -len(ext)] + ".xdmf"
    return path + ".xdmf"


def check_xdmf(c, path, n, frames, paraview=False):
    """Checks the XDMF sidecar against the HDF5 file; optionally loads it in ParaView."""
    import os
    import xml.etree.ElementTree as ET

    xdmf = xdmf_path_for(path)
    if not os.path.exists(xdmf):
        c.warn(f"no XDMF sidecar {xdmf}")
        return
    try:
        root = ET.parse(xdmf).getroot()
    except ET.ParseError as exc:
        c.fail(f"{xdmf} is not valid XML ({exc})")
        return
    grids = [g for g in root.iter("Grid") if g.get("GridType") == "Uniform"]
    if len(grids) > frames:
        c.fail(f"{xdmf} describes {len(grids)} frames, the file has {frames}")
    elif len(grids) < frames:  # a running writer refreshes the sidecar every 100 frames past 1000
        c.warn(f"{xdmf} describes {len(grids)} of {frames} frames "
               "(stale until the writer flushes or closes)")
    base = os.path.dirname(os.path.abspath(xdmf))
    with h5py.File(path, "r") as f:
        for g in grids[:1] + grids[-1:]:
            topo = g.find("Topology")
            if (topo is None or topo.get("TopologyType") != "Polyvertex"
                    or topo.get("NumberOfElements") != str(n)):
                c.fail(f"{xdmf} grid {g.get('Name')}: "
                       f"expected a Polyvertex topology of {n} elements")
            for item in g.iter("DataItem"):
                if item.get("Format") != "HDF":
                    continue
                fname, _, dset = item.text.strip().partition(":")
                if (os.path.normpath(os.path.join(base, fname))
                        != os.path.normpath(os.path.abspath(path))):
                    c.fail(f"{xdmf} refers to {fname}, not {os.path.basename(path)}")
                elif dset not in f:
                    c.fail(f"{xdmf} refers to missing dataset {dset}")
                elif ([int(x) for x in item.get("Dimensions").split()][1:]
                      != list(f[dset].shape[1:])):
                    c.fail(f"{xdmf}: Dimensions of {dset} do not match the file")
    if not paraview:
        return
    try:
        from paraview import servermanager as sm
        from paraview.simple import XDMFReader
        from vtk.numpy_interface import dataset_adapter as dsa
    except Exception:
        c.warn("ParaView's Python module is not available: sidecar not loaded")
        return
    r = XDMFReader(FileNames=[os.path.abspath(xdmf)])
    r.UpdatePipelineInformation()
    times = list(r.TimestepValues) if frames > 1 else [0.0]
    if frames > 1 and len(times) != frames:
        c.fail(f"ParaView sees {len(times)} time steps in {xdmf}, expected {frames}")
        return
    if frames == 0:
        return
    r.UpdatePipeline(times[-1])
    d = sm.Fetch(r)
    if d.IsA("vtkMultiBlockDataSet"):
        d = d.GetBlock(0)
    pts = np.array(dsa.WrapDataObject(d).Points)
    with h5py.File(path, "r") as f:
        ref = f["particles/all/position/value"][frames - 1] if "particles/all" in f else None
    if d.GetNumberOfPoints() != n or ref is None or not np.array_equal(pts, ref):
        c.fail(f"ParaView's XDMF Reader does not reproduce the last frame's positions from {xdmf}")
    else:
        print(f"ParaView XDMF Reader: {frames} time steps, {d.GetNumberOfPoints()} points, "
              "last frame exact")


def mdanalysis_check(c, path, n, frames):
    """Opens the file with MDAnalysis' H5MD reader when MDAnalysis is installed."""
    try:
        from MDAnalysis.coordinates.H5MD import H5MDReader
    except Exception:  # MDAnalysis is optional
        return
    try:
        r = H5MDReader(path, convert_units=False)
        if r.n_atoms != n or r.n_frames != frames:
            c.fail(f"MDAnalysis reads {r.n_atoms} atoms and {r.n_frames} frames")
        r.close()
    except Exception as exc:
        c.fail(f"MDAnalysis' H5MDReader(convert_units=False) fails: {exc}")


def report(c, path, n, frames, box_L, verbose):
    if verbose:
        print(f"{path}")
        if n is not None:
            print(f"N = {n}")
            print(f"frames = {frames}")
        if box_L is not None and len(box_L) > 0:
            lo, hi = float(np.min(box_L)), float(np.max(box_L))
            print(f"box = {lo!r}" if lo == hi else f"box = {lo!r} .. {hi!r}")
    for w in c.warnings:
        print(f"warning: {w}", file=sys.stderr)
    for p in c.problems:
        print(f"problem: {p}", file=sys.stderr)
    if c.problems:
        print(f"{path}: {len(c.problems)} problem(s)", file=sys.stderr)
        return 1
    if verbose:
        print("layout OK")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("file", help="H5MD trajectory (traj.h5)")
    ap.add_argument("--group", default=None,
                    help="particle group under /particles (default: the first)")
    ap.add_argument("--quiet", action="store_true", help="print problems only")
    ap.add_argument("--paraview", action="store_true",
                    help="also load the XDMF sidecar with ParaView's XDMF Reader "
                         "(needs paraview's Python module)")
    args = ap.parse_args()
    sys.exit(check(args.file, args.group, verbose=not args.quiet, paraview=args.paraview))


if __name__ == "__main__":
    main()
