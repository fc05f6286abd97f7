"""cablesim: nonlinear statics and dynamics of weightless sagging elasto-flexible cables.

A planar cable is fixed at support A = (0, 0) and support B = (L, H) and carries n lumped
masses at its interior nodes. The vertical axis points *down* (along gravity-like loads), so
``H > 0`` puts B below A and a positive vertical load pulls a node down. SI units throughout.

Python API (the command line's analyses; see :mod:`cablesim.api`)::

    import cablesim
    case = cablesim.load_case("my-case.yaml")     # or a dict, or None for the paper's example
    st = cablesim.static(case)                     # StaticRun: .result, .to_hdf5(path), .plot(png)
    h = cablesim.history(case, omega=2.4, duration=600.0)   # HistoryRun: .history, .to_hdf5(path)
    fv = cablesim.free_vibration(case, mode=3, peak_velocity=1.0)
    sw = cablesim.sweep(case, jobs=2)              # SweepRun: .result, .to_hdf5(path)
    bb = cablesim.backbone(case, mode=1, amplitude=5.0)   # BackboneRun: free undamped orbits of mode 1
    cablesim.plot(["sweep.h5"], "sweep.png", stamp="preview: coarse grid")   # redraw stored results
    r = cablesim.load_result("sweep.h5")           # any result file: r.arrays, r["sweep/amplitude"], r.data
    ds = r.to_xarray()                             # an xarray.Dataset (omega x channel), if xarray is installed
    st.plot_modes("modes.png", count=4)           # the lowest mode shapes: a matplotlib Figure
    cablesim.animate("history.h5", "history.gif")  # the cable moving: a matplotlib FuncAnimation
    cablesim.report(["static.h5", "history.h5"], "report.html")   # one self-contained HTML page

The package, from the bottom layer up (a module imports only from layers below it; checked by
``tests/test_architecture.py``):

- ``names``, ``errors``, ``version``, ``channels`` -- the vocabulary; ``jit`` -- the decorator of
  every compiled kernel, whose on-disk cache is keyed on a hash of the compiled sources, and the
  watch on what numba compiles; ``blas`` -- the BLAS libraries held to one thread while orbits
  are traced; ``roots`` -- Brent's bracketed root (as scipy computes it);
- ``cable`` -- the model's data: geometry, axial rigidity, masses, the degree-of-freedom order;
- ``mechanics/`` -- the cable's physics written once for any number of components per node: the
  segment law, its assembly, the closure problem on the complementary energy, the approximate
  analysis' flexibility, the compiled model's named constants;
- ``statics``, ``modal`` -- the three static equilibria, modes and Rayleigh damping;
- ``dynamics/`` -- the equations of motion (``equations``) and their compiled vector field
  (``field``), the integrators (``integrators/``), time histories (``simulate``, in chunks bounded
  in steps), steady states (``steady``), spectra, run status (``status``), Ctrl-C and SIGTERM (``interrupts``); it never
  sees a case file;
- ``orbits/`` -- periodic orbits by shooting, Floquet multipliers, continuation, bifurcations,
  bifurcation curves in two parameters and backbone curves;
- ``case`` -- YAML case files (strict YAML: ``strict_yaml``; numbers in stated ranges:
  ``numbers``) validated into a frozen :class:`~cablesim.case.Case`;
- ``analyses/`` -- case in, result out: ``setup`` (equations, integrator and step rules, once),
  ``static``, ``dynamic``, ``sweep`` (its points: ``sweep_points``; its refinement: ``refine``;
  its worker processes: ``pool``), ``continuation``, ``charts`` (bifurcation curves, backbones),
  ``cost`` (estimates before a run); no drawing, no files;
- ``io/`` -- HDF5 writers and readers (``hdf5``, the only h5py), sweep journal, text summaries,
  output paths checked and locked (``paths``), default result names (``naming``), the record of
  each run (``provenance``), progress and the compile notice (``terminal``), the steps the
  time-history commands share (``finish``), any result file read as one object (``results``) and
  exported as CSV files (``export``);
- ``plots/`` -- every PNG (the only matplotlib);
- ``stress/`` -- numerical stability across parameter ranges (``cablesim stress``);
- ``api`` and ``cli`` -- the Python API and the ``cablesim`` command (``cli_charts``: its
  design-chart commands, ``cablesim backbone`` and the charts of ``cablesim continue``;
  ``cli_results``: ``cablesim export`` and ``cablesim rerun``; ``cli_figures``: ``--format``,
  ``--width`` and ``--dpi`` on every command that draws; ``cli_views``: the commands that show
  results, ``cablesim animate`` and ``cablesim report``; ``warmup``: ``cablesim compile``'s
  tiny runs; ``cli_guard``: the checks of ``cablesim continue``'s inputs before it computes,
  and its run).
"""

from .version import __version__

_API = ("load_case", "static", "history", "free_vibration", "sweep", "continuation", "backbone", "plot", "animate", "report",
        "export_csv", "rerun", "compile_kernels", "load_result", "ResultFile", "StaticRun", "HistoryRun", "SweepRun", "ContinuationRun", "BackboneRun")

__all__ = ["__version__", *_API]


def __dir__() -> list[str]:
    # The API's names too, though they load only on first use.
    return sorted({*globals(), *__all__})


def __getattr__(name: str):
    # The API pulls in numba and scipy; load it on first use so `import cablesim` stays light.
    if name == "compile_kernels":
        from .warmup import compile_kernels

        return compile_kernels
    if name in _API:
        from . import api

        return getattr(api, name)
    raise AttributeError(f"module 'cablesim' has no attribute {name!r}")
