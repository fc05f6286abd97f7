"""The cable's mechanics, written once for any number of components per node (``DIM``).

One floor above :mod:`cablesim.cable` and below the statics, the dynamics and the orbits, which
all call it (nothing reaches into another module's kernels):

- ``vectors`` -- small vectors and blocks of ``DIM`` components as tuples (``DIM`` is part of
  their type, so each kernel is compiled once per ``DIM``, with every component loop unrolled);
- ``segments`` -- the segment law: length, unit vector, tension ``EA (l - S) / S``
  (tension-only), the tangent block ``(EA/S) e e^T + (T/l)(I - e e^T)``, gaps and slack modes;
- ``assembly`` -- the segments assembled into the resisting force, the product ``K v`` without a
  matrix, the dense and the banded tangent, and the orbits' Jacobian blocks;
- ``banded`` -- the general band storage of those matrices (half bandwidth ``2 DIM - 1``), its
  products and O(n) solves;
- ``closure`` -- the closure problem on the convex complementary energy (``DIM`` unknowns: the
  force in the first segment), compiled;
- ``equilibrium`` -- that closure for the statics: scaled, checked for slack, explained;
- ``flexibility`` -- the approximate analysis' flexibility ``N = D + f`` and stiffness
  ``K = N^-1`` in factored, O(n) form, and the dense matrices column by column;
- ``linalg`` -- small dense solves inside compiled loops;
- ``model`` -- the compiled physics' named constants (:class:`~.model.CableModel`) and scratch
  space (:class:`~.model.Workspace`).
"""
