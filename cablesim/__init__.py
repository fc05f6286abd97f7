"""cablesim: nonlinear statics and dynamics of weightless sagging elasto-flexible cables.

A planar cable is fixed at support A = (0, 0) and support B = (L, H) and carries n lumped
masses at its interior nodes. The vertical axis points *down* (along gravity-like loads), so
``H > 0`` puts B below A and a positive vertical load pulls a node down.

The layers, from the bottom up:

- :mod:`cablesim.cable` -- the cable model (geometry, EA, masses, degree-of-freedom order);
- :mod:`cablesim.statics` -- inextensible, approximate-elastic and exact-elastic equilibria;
- :mod:`cablesim.modal` -- modal analysis and Rayleigh damping;
- :mod:`cablesim.case` -- YAML case files validated into a frozen case model;
- :mod:`cablesim.io_hdf5`, :mod:`cablesim.plotting` -- writers;
- :mod:`cablesim.cli` -- the ``cablesim`` command.
"""

__version__ = "0.1.0"
