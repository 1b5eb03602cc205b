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
