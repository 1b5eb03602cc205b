"""Whole-fabric arrays as numpy views of copies made in C++ (no Python loop over nodes). SI units."""
import numpy as np


def positions(engine):
    """Node positions, shape (n_nodes, 3) [m]."""
    return np.frombuffer(engine._positions(), dtype=np.float64).reshape(-1, 3)


def velocities(engine):
    """Node velocities at the current step, shape (n_nodes, 3) [m/s]."""
    return np.frombuffer(engine._velocities(), dtype=np.float64).reshape(-1, 3)


def strains(engine):
    """Element strains (l - l0)/l0, shape (n_elements,) [-]."""
    return np.frombuffer(engine._strains(), dtype=np.float64)


def tensions(engine):
    """Element axial forces, positive in tension, shape (n_elements,) [N]."""
    return np.frombuffer(engine._tensions(), dtype=np.float64)


def masses(engine):
    """Lumped node masses, shape (n_nodes,) [kg]."""
    return np.frombuffer(engine._masses(), dtype=np.float64)


def rest_lengths(engine):
    """Element rest lengths l0, shape (n_elements,) [m]."""
    return np.frombuffer(engine._rest_lengths(), dtype=np.float64)


def section_flattening(engine):
    """Cross-sectional deformation eps = 1 - b/r0 of every node, shape (n_nodes,) [-]."""
    return np.frombuffer(engine._section_flattening(), dtype=np.float64)


def section_semi_axes(engine):
    """Section semi-axes (a, b) of every node under the collision stage's rule, shape (n_nodes, 2) [m]."""
    return np.frombuffer(engine._section_semi_axes(), dtype=np.float64).reshape(-1, 2)


def contacts(engine):
    """Contacts of the last step: columns cpA, cpB, gap [m] (< 0: overlap), normal x, y, z, sA, sB (the
    contact point along each CP), kind (0 paper, 1 crossing CP pair, 2 side by side, 3 persistent crossing), hA, hB [m] (each section's
    measure along the normal: the gap is the axes' distance less hA + hB; 0 in the paper's model);
    shape (n, 11)."""
    return np.frombuffer(engine._contacts(), dtype=np.float64).reshape(-1, 11)


def crossings(engine):
    """The persistent crossings (contact_model='gap', crossings='persistent'): columns cpA, sA, cpB, sB (the
    sliding coordinates: a CP and the place along it), normal x, y, z (the side B lies on, seen from A),
    measure [m] (the sections' hA + hB at the last step), impulse [N s] (the last step's normal impulse:
    the warm start); shape (n, 9)."""
    return np.frombuffer(engine._crossings(), dtype=np.float64).reshape(-1, 9)


def candidate_pairs(engine, broad_phase='tree'):
    """CP pairs (a < b) whose broad-phase boxes overlap now, from 'tree' or 'sap'; shape (n, 2)."""
    return np.frombuffer(engine._candidate_pairs(broad_phase), dtype=np.int32).reshape(-1, 2)


def section_dirs(engine):
    """Unit minor-axis (flattened) direction of every node's section, shape (n_nodes, 3) [-]."""
    return np.frombuffer(engine._section_dirs(), dtype=np.float64).reshape(-1, 3)


def alive(engine):
    """1 for every element (CP) still whole, 0 for a broken one, shape (n_elements,)."""
    return np.frombuffer(engine._alive(), dtype=np.uint8)


def filtered_strains(engine):
    """The breakage filter's strain of every element, shape (n_elements,) [-] (empty with breakage off)."""
    return np.frombuffer(engine._filtered_strains(), dtype=np.float64)


def body_contacts(engine):
    """Contacts of CPs with rigid bodies in the last step: structured array with cp, body, part, gap [m],
    normal (3), point (3) [m], s, time [s]."""
    a = np.frombuffer(engine._body_contacts(), dtype=np.float64).reshape(-1, 12)
    return {'cp': a[:, 0].astype(int), 'body': a[:, 1].astype(int), 'part': a[:, 2].astype(int), 'gap': a[:, 3],
            'normal': a[:, 4:7], 'point': a[:, 7:10], 's': a[:, 10], 'time': a[:, 11]}
