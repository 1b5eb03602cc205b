"""Pictures of the deformed pack, rendered off-screen with the VTK library (python3-vtk9): yarns as
tubes coloured by strain, broken ends as red balls, the projectile in grey, seen from behind the ply.

    paths = woven.render.write_frame(engine, 'out/ballistic/pictures', 'pack_025us')   # .vtp files
    woven.render.render([(paths, 'out/ballistic/pack_025us.png', 't = 25.0 us')], strain_max=0.05)

Debian's VTK 9.1 renders through X only (no OSMesa or EGL window), so `render` runs this file as a
child process: under the session's DISPLAY if there is one, else under `xvfb-run` (a private X
server in memory). The child needs only vtk, so a crash of the renderer never takes the scene with it.
"""
import json
import os
import shutil
import subprocess
import sys


def write_frame(engine, directory, stem, rings=8):
    """Writes the yarn tubes, the bodies and the broken ends of `engine` as it stands into
    DIRECTORY/STEM_{yarns,bodies,ends}.vtp; returns the three paths."""
    import numpy as np
    import vtk
    from vtk.util import numpy_support as ns
    from . import arrays
    from .vtk_output import body_surfaces, write_polydata, yarn_tubes
    os.makedirs(directory, exist_ok=True)
    e0 = np.frombuffer(engine._element_first_nodes(), dtype=np.int32)
    broken = np.nonzero(arrays.alive(engine) == 0)[0]
    X = arrays.positions(engine)
    ends = vtk.vtkPolyData()
    pts = vtk.vtkPoints()
    P = np.concatenate([X[e0[broken]], X[e0[broken] + 1]]) if len(broken) else np.zeros((0, 3))
    pts.SetData(ns.numpy_to_vtk(np.ascontiguousarray(P), deep=True))
    ends.SetPoints(pts)
    paths = []
    for part, poly in (('yarns', yarn_tubes(engine, rings)), ('bodies', body_surfaces(engine)), ('ends', ends)):
        path = os.path.join(directory, '%s_%s.vtp' % (stem, part))
        write_polydata(poly, path)
        paths.append(path)
    return paths


def render(jobs, strain_max=0.05, size=(1200, 900), timeout=600):
    """Renders each job (frame paths from write_frame, png path, title) to its PNG in one child
    process (see the module doc). strain_max [-]: top of the colour scale (the failure strain: the
    frames share it). Raises RuntimeError with the child's message when a picture is not written."""
    job = {'jobs': [[list(p), png, title] for p, png, title in jobs], 'strain_max': float(strain_max),
           'size': [int(size[0]), int(size[1])]}
    cmd = [sys.executable if os.path.basename(sys.executable).startswith('python') else '/usr/bin/python3',
           os.path.abspath(__file__), json.dumps(job)]
    if not os.environ.get('DISPLAY'):
        if not shutil.which('xvfb-run'):
            raise RuntimeError('pictures need an X display or xvfb-run (apt-get install xvfb); set pictures=0')
        cmd = ['xvfb-run', '-a', '-s', '-screen 0 %dx%dx24' % (size[0] + 64, size[1] + 64)] + cmd
    env = dict(os.environ)
    env.pop('PYTHONSTARTUP', None)
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    missing = [png for _, png, _ in jobs if not os.path.exists(png)]
    if r.returncode != 0 or missing:
        raise RuntimeError('the renderer failed (exit %d, %d pictures missing): %s'
                           % (r.returncode, len(missing), (r.stderr or r.stdout)[-2000:]))
    return [png for _, png, _ in jobs]


class Pictures:
    """`count` pictures of a run: frames taken at t_end k / count (k = 1 .. count - 1, as the run
    passes them) and at the end, rendered together by finish() into DIRECTORY/pack_<time>us.png (the
    frames' .vtp files in DIRECTORY/pictures)."""

    def __init__(self, engine, directory, t_end, count, rings=8):
        if not (isinstance(count, int) and 1 <= count <= 100):
            raise ValueError('pictures = %r is invalid: allowed 0 (none) or [1, 100]' % (count,))
        self.engine, self.dir, self.rings = engine, directory, rings
        self.times = [t_end * k / count for k in range(1, count)]
        self.interval = t_end / count
        self.frames = []  # (paths, time)

    def due(self, time):
        """Takes a frame when the run has passed the next picture time [s]."""
        if self.times and time >= self.times[0]:
            while self.times and time >= self.times[0]:
                self.times.pop(0)
            self.take(time)

    def take(self, time):
        stem = 'pack_%06.2fus' % (1e6 * time)
        self.frames.append((write_frame(self.engine, os.path.join(self.dir, 'pictures'), stem, self.rings), time))

    def finish(self, time, strain_max, title=''):
        """The last frame at `time` [s] (it replaces a frame taken within half a picture interval
        before it), then every picture; returns the PNG paths."""
        if self.frames and time - self.frames[-1][1] < 0.5 * self.interval:
            self.frames.pop()
        self.take(time)
        jobs = [(paths, os.path.join(self.dir, os.path.basename(paths[0])[:-len('_yarns.vtp')] + '.png'),
                 '%st = %.1f us' % (title, 1e6 * t)) for paths, t in self.frames]
        pngs = render(jobs, strain_max=strain_max)
        # The frames were only the renderer's input (3 MB each for the default ply; vtk_every keeps
        # ParaView's): gone once their pictures exist. A failed render leaves them to look at.
        for paths, _ in self.frames:
            for p in paths:
                os.remove(p)
        try:
            os.rmdir(os.path.join(self.dir, 'pictures'))
        except OSError:
            pass
        return pngs


def _draw(paths, png, title, strain_max, size):
    """One picture (in the child): the ply's tubes by strain, the ends, the bodies, from behind."""
    import vtk

    def read(path):
        r = vtk.vtkXMLPolyDataReader()
        r.SetFileName(path)
        r.Update()
        return r.GetOutput()

    yarns, bodies, ends = (read(p) for p in paths)
    ren = vtk.vtkRenderer()
    ren.SetBackground(1, 1, 1)
    lut = vtk.vtkLookupTable()
    lut.SetHueRange(0.667, 0.0)  # blue (slack) to red (failure strain)
    lut.SetTableRange(0, strain_max)
    lut.Build()
    m = vtk.vtkPolyDataMapper()
    m.SetInputData(yarns)
    m.SetScalarModeToUseCellFieldData()
    m.SelectColorArray('strain')
    m.SetLookupTable(lut)
    m.SetScalarRange(0, strain_max)
    m.ScalarVisibilityOn()
    a = vtk.vtkActor()
    a.SetMapper(m)
    ren.AddActor(a)
    bounds = yarns.GetBounds()
    span = max(bounds[1] - bounds[0], bounds[3] - bounds[2], 1e-6)
    if bodies.GetNumberOfPoints():
        mb = vtk.vtkPolyDataMapper()
        mb.SetInputData(bodies)
        ab = vtk.vtkActor()
        ab.SetMapper(mb)
        ab.GetProperty().SetColor(0.55, 0.55, 0.58)
        ab.GetProperty().SetOpacity(0.6)
        ren.AddActor(ab)
    if ends.GetNumberOfPoints():
        ball = vtk.vtkSphereSource()
        ball.SetRadius(0.006 * span)
        g = vtk.vtkGlyph3D()
        g.SetInputData(ends)
        g.SetSourceConnection(ball.GetOutputPort())
        g.SetScaleModeToDataScalingOff()
        me = vtk.vtkPolyDataMapper()
        me.SetInputConnection(g.GetOutputPort())
        me.ScalarVisibilityOff()
        ae = vtk.vtkActor()
        ae.SetMapper(me)
        ae.GetProperty().SetColor(0.9, 0.0, 0.0)
        ren.AddActor(ae)
    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle('strain')
    bar.SetNumberOfLabels(6)
    bar.SetLabelFormat('%.3f')
    bar.GetTitleTextProperty().SetColor(0, 0, 0)
    bar.GetLabelTextProperty().SetColor(0, 0, 0)
    bar.SetWidth(0.08)
    bar.SetHeight(0.6)
    bar.SetPosition(0.9, 0.2)
    ren.AddViewProp(bar)
    text = vtk.vtkTextActor()
    text.SetInput(title + '   (seen from behind the ply; red balls: broken ends)')
    text.GetTextProperty().SetColor(0, 0, 0)
    text.GetTextProperty().SetFontSize(20)
    text.SetPosition(12, 12)
    ren.AddViewProp(text)
    # From behind (the side the projectile pushes the cone out of), 20 degrees below the ply's plane:
    # low enough to see the cone's profile, high enough to see the strain over the ply.
    cx, cy, cz = (0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]), bounds[5])
    cam = ren.GetActiveCamera()
    cam.SetFocalPoint(cx, cy, cz)
    cam.SetPosition(cx + 0.6 * span, cy - 1.6 * span, cz - 0.62 * span)
    cam.SetViewUp(0, 0, -1)
    ren.ResetCamera()
    cam.Zoom(1.25)
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.AddRenderer(ren)
    win.SetSize(*size)
    win.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(win)
    grab.Update()
    tmp = png + '.tmp.png'
    w = vtk.vtkPNGWriter()
    w.SetFileName(tmp)
    w.SetInputConnection(grab.GetOutputPort())
    w.Write()
    os.replace(tmp, png)


if __name__ == '__main__':
    spec = json.loads(sys.argv[1])
    for paths, png, title in spec['jobs']:
        _draw(paths, png, title, spec['strain_max'], tuple(spec['size']))
