"""The BLAS threads of numpy and scipy while cablesim computes.

cablesim's dense linear algebra is on small matrices: the Rayleigh-Ritz projections of the
leading Floquet multipliers (at most 160 square), the bordered systems of GMRES, monodromies of
at most 40 states. On these OpenBLAS's threads save no time, and after each call they wait for
the next by spinning, which costs the CPU time of a core while the compiled kernels run on the
other: on the 50-node heavy span (``benchmarks/bench_heavy_orbits.py``) the continuation takes
the same wall time with one BLAS thread as with two, and a third less CPU time
(``benchmarks/README.md``). :func:`one_blas_thread` limits the BLAS libraries numpy and scipy
loaded to one thread for a computation, and gives back the user's setting after it.
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import Iterator


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the body with every loaded BLAS library (numpy's, scipy's) on one thread."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        yield
