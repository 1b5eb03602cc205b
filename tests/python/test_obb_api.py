"""The narrow phase from Python, for a single pair of boxes: YADE's Vector3/Matrix3 in, figures out."""
import math

import pytest


def test_face_contact_and_swept_contact(yade_ns):
    import woven
    from yade import Vector3, Matrix3
    I = Matrix3.Identity
    # a unit cube 0.1 m deep in a slab: depth 0.1 along +z, four contact points on the cube's bottom
    c = woven.obb_contact(Vector3(0, 0, 0), I, Vector3(2, 2, 0.5), Vector3(0.2, -0.3, 0.9), I, Vector3(0.5, 0.5, 0.5))
    assert c['overlap'] and c['axis'] == 2
    assert c['depth'] == pytest.approx(0.1, abs=1e-12)
    assert type(c['normal']).__name__ == 'Vector3' and c['normal'][2] == pytest.approx(1.0)
    assert len(c['points']) == 4 and all(p[1][2] == pytest.approx(0.4) for p in c['points'])
    # the same cube falling from 1 m above at 10 m/s touches after (1 - 0.5 - 0.5 + 0.1)/10... i.e. at
    # gap / speed, with gap = 0.9 + 1 - 0.5 - 0.5 = 0.9 m -> 0.09 s
    s = woven.obb_first_contact(Vector3(0, 0, 0), I, Vector3(2, 2, 0.5), Vector3(0, 0, 0),
                                Vector3(0, 0, 1.9), I, Vector3(0.5, 0.5, 0.5), Vector3(0, 0, -10), 0.1)
    assert s['hit'] and s['time'] == pytest.approx(0.09, abs=1e-12)
    assert s['contact']['depth'] == pytest.approx(0.0, abs=1e-9)
    # a rotated box: axes are the columns of the matrix
    R = Matrix3(math.cos(0.3), -math.sin(0.3), 0, math.sin(0.3), math.cos(0.3), 0, 0, 0, 1)
    c = woven.obb_contact(Vector3(0, 0, 0), R, Vector3(1, 1, 1), Vector3(3, 0, 0), I, Vector3(1, 1, 1))
    assert not c['overlap']


def test_bad_boxes_are_refused(yade_ns):
    import woven
    from yade import Vector3, Matrix3
    I = Matrix3.Identity
    with pytest.raises(ValueError, match='axes'):
        woven.obb_contact(Vector3(0, 0, 0), Matrix3(2, 0, 0, 0, 1, 0, 0, 0, 1), Vector3(1, 1, 1),
                          Vector3(0, 0, 0), I, Vector3(1, 1, 1))
    with pytest.raises(ValueError, match='extents'):
        woven.obb_contact(Vector3(0, 0, 0), I, Vector3(-1, 1, 1), Vector3(0, 0, 0), I, Vector3(1, 1, 1))
