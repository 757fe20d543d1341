"""Systems: the affine discrete-time plant with bounded noise, its noise descriptions, system files and the
papers' example plants (one home for them).

:mod:`~eqrec.systems.affine`
    :class:`~eqrec.systems.affine.AffineSystem`, ``x(t+1) = A x + B u + f + E w``, ``y = C x + V v``, with its box.
:mod:`~eqrec.systems.noise`
    Noise descriptions of one system: the box, Gaussian second moments, multiplicative terms.
:mod:`~eqrec.systems.files`
    System files (YAML or a mapping) to an ``AffineSystem``.
:mod:`~eqrec.systems.examples`
    The example plants: the ACC model (P1), the batch reactor (P3), two carts and a spring (``two_mass``).
"""
