"""ParaView output with the VTK library (Debian's python3-vtk9): yarns as tubes with their elliptic
sections, and the rigid bodies, one .vtp pair per frame and a .pvd collection with the times.

    rec = woven.vtk_output.Recorder('out/ballistic/vtk', engine, rings=8)
    rec.write(time)          # yarns_00000.vtp, bodies_00000.vtp; rec.close() writes frames.pvd

Each node gets a ring of `rings` points on its section's ellipse (major semi-axis a across the yarn
and its flattened direction, minor b along it, from the collision stage's section rule); the rings
of the two nodes of every whole CP are joined by quads. Cell data: strain, broken filter strain,
yarn; point data: velocity [m/s]. SI units throughout.
"""
import os

import numpy as np

from . import arrays
from .output import atomic_open, atomic_path


def _vtk():
    try:
        import vtk  # noqa: F401
        from vtk.util import numpy_support  # noqa: F401
        return vtk, numpy_support
    except ImportError as ex:  # pragma: no cover - set-up installs python3-vtk9
        raise ImportError('VTK output needs the VTK library: apt-get install python3-vtk9') from ex


def write_polydata(poly, path):
    """Writes vtkPolyData `poly` to `path` (.vtp, appended, zlib), atomically."""
    vtk, _ = _vtk()
    with atomic_path(path) as tmp:
        w = vtk.vtkXMLPolyDataWriter()
        w.SetFileName(tmp)
        w.SetInputData(poly)
        w.SetDataModeToAppended()
        w.SetCompressorTypeToZLib()
        if not w.Write():
            raise IOError('VTK could not write %s' % path)


def yarn_tubes(engine, rings=8):
    """vtkPolyData of the yarns as elliptic tubes (see the module doc)."""
    vtk, ns = _vtk()
    X = arrays.positions(engine)
    n = len(X)
    ab = arrays.section_semi_axes(engine)
    D = arrays.section_dirs(engine)
    e0 = np.frombuffer(engine._element_first_nodes(), dtype=np.int32)
    live = arrays.alive(engine).astype(bool)
    # Tangent per node: mean of the adjoining CP directions (the end node takes its one CP).
    T = np.zeros_like(X)
    d = X[e0 + 1] - X[e0]
    d /= np.linalg.norm(d, axis=1)[:, None]
    np.add.at(T, e0, d)
    np.add.at(T, e0 + 1, d)
    T /= np.maximum(np.linalg.norm(T, axis=1), 1e-300)[:, None]
    Dn = D - np.sum(D * T, axis=1)[:, None] * T
    Dn /= np.maximum(np.linalg.norm(Dn, axis=1), 1e-300)[:, None]
    U = np.cross(T, Dn)
    phi = 2 * np.pi * np.arange(rings) / rings
    P = (X[:, None, :] + (ab[:, 0, None, None] * np.cos(phi)[None, :, None]) * U[:, None, :]
         + (ab[:, 1, None, None] * np.sin(phi)[None, :, None]) * Dn[:, None, :]).reshape(-1, 3)
    el = np.nonzero(live)[0]
    a0 = e0[el].astype(np.int64) * rings
    k = np.arange(rings)
    k1 = (k + 1) % rings
    quads = np.stack([a0[:, None] + k, a0[:, None] + k1, a0[:, None] + rings + k1, a0[:, None] + rings + k], axis=2)
    quads = quads.reshape(-1, 4)
    cells = np.hstack([np.full((len(quads), 1), 4, np.int64), quads]).ravel()
    poly = vtk.vtkPolyData()
    pts = vtk.vtkPoints()
    pts.SetData(ns.numpy_to_vtk(np.ascontiguousarray(P), deep=True))
    poly.SetPoints(pts)
    ca = vtk.vtkCellArray()
    ca.SetCells(len(quads), ns.numpy_to_vtkIdTypeArray(cells.astype(ns.ID_TYPE_CODE), deep=True))
    poly.SetPolys(ca)
    V = np.repeat(arrays.velocities(engine), rings, axis=0)
    va = ns.numpy_to_vtk(np.ascontiguousarray(V), deep=True)
    va.SetName('velocity')
    poly.GetPointData().AddArray(va)
    strain = np.repeat(arrays.strains(engine)[el], rings)
    sa = ns.numpy_to_vtk(np.ascontiguousarray(strain), deep=True)
    sa.SetName('strain')
    poly.GetCellData().AddArray(sa)
    fs = arrays.filtered_strains(engine)
    if len(fs) == len(live):
        fa = ns.numpy_to_vtk(np.ascontiguousarray(np.repeat(fs[el], rings)), deep=True)
        fa.SetName('filtered_strain')
        poly.GetCellData().AddArray(fa)
    assert n * rings == len(P)
    return poly


def body_surfaces(engine):
    """vtkPolyData of the coupled rigid bodies' parts (boxes, spheres, cylinders, triangles) at their current pose."""
    vtk, _ = _vtk()
    app = vtk.vtkAppendPolyData()
    count = 0
    tri = vtk.vtkPolyData()  # the meshes' triangles, as they are (corners in the global frame)
    tri_points, tri_cells = vtk.vtkPoints(), vtk.vtkCellArray()
    for k in range(engine.n_bodies):
        for (kind, size, centre, axes) in engine._body_parts(k):
            if kind in ('triangle', 'facet'):
                tri_cells.InsertNextCell(3)
                for v in size:
                    tri_cells.InsertCellPoint(tri_points.InsertNextPoint(v[0], v[1], v[2]))
                continue
            if kind == 'box':
                src = vtk.vtkCubeSource()
                src.SetXLength(2 * size[0]), src.SetYLength(2 * size[1]), src.SetZLength(2 * size[2])
            elif kind == 'cylinder':  # (radius, half_length, chisel_angle, land_half_width): the round
                # cylinder (a chisel's flats are not cut in the picture); VTK's axis is y, the part's z
                src = vtk.vtkCylinderSource()
                src.SetRadius(size[0]), src.SetHeight(2 * size[1]), src.SetResolution(32)
                axes = [[row[0], row[2], -row[1]] for row in axes]  # turn VTK's y onto the part's z
            else:
                src = vtk.vtkSphereSource()
                src.SetRadius(size), src.SetThetaResolution(24), src.SetPhiResolution(12)
            m = vtk.vtkMatrix4x4()
            for i in range(3):
                for j in range(3):
                    m.SetElement(i, j, axes[i][j])
                m.SetElement(i, 3, centre[i])
            tr = vtk.vtkTransform()
            tr.SetMatrix(m)
            f = vtk.vtkTransformPolyDataFilter()
            f.SetTransform(tr)
            f.SetInputConnection(src.GetOutputPort())
            f.Update()
            app.AddInputData(f.GetOutput())
            count += 1
    if tri_cells.GetNumberOfCells():
        tri.SetPoints(tri_points), tri.SetPolys(tri_cells)
        app.AddInputData(tri)
        count += 1
    if count == 0:
        return vtk.vtkPolyData()
    app.Update()
    return app.GetOutput()


class Recorder:
    """Writes frames into `directory` and a frames.pvd collection that ParaView opens as a time series."""

    def __init__(self, directory, engine, rings=8):
        if rings < 3:
            raise ValueError('vtk_rings = %r is invalid: allowed [3, inf) points per section' % rings)
        self.dir, self.engine, self.rings = directory, engine, rings
        os.makedirs(directory, exist_ok=True)
        self.frames = []

    def write(self, time):
        i = len(self.frames)
        names = []
        for stem, poly in (('yarns', yarn_tubes(self.engine, self.rings)), ('bodies', body_surfaces(self.engine))):
            name = '%s_%05d.vtp' % (stem, i)
            write_polydata(poly, os.path.join(self.dir, name))
            names.append(name)
        self.frames.append((time, names))
        self.close()
        return [os.path.join(self.dir, n) for n in names]

    def close(self):
        with atomic_open(os.path.join(self.dir, 'frames.pvd')) as f:
            f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n')
            for t, names in self.frames:
                for part, n in enumerate(names):
                    f.write('<DataSet timestep="%.9g" part="%d" file="%s"/>\n' % (t, part, n))
            f.write('</Collection>\n</VTKFile>\n')


def read(path):
    """Reads a .vtp back (for tests and post-processing): vtkPolyData."""
    vtk, _ = _vtk()
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()
