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
    """Contacts of the last step: columns cpA, cpB, gap [m] (< 0: overlap), normal x, y, z; shape (n, 6)."""
    return np.frombuffer(engine._contacts(), dtype=np.float64).reshape(-1, 6)


def candidate_pairs(engine, broad_phase='tree'):
    """CP pairs (a < b) whose broad-phase boxes overlap now, from 'tree' or 'sap'; shape (n, 2)."""
    return np.frombuffer(engine._candidate_pairs(broad_phase), dtype=np.int32).reshape(-1, 2)
