"""The result of every design method: gains, levels, solver record and certificate."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from eqrec.bounds.gains import GainSchedule
from eqrec.lp.model import LPSolution
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.words import as_pattern
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError
from eqrec.design.report import node_level  # the level the estimator reports (its one implementation)

if TYPE_CHECKING:
    from eqrec.estimators.guaranteed import GuaranteedEstimator
    from eqrec.design.weighted import WeightedEstimator


class ClassLevels:
    """The level of an observed prefix in a class-engine design: the certified level of its class.

    The rule ``bound_of(prefix) -> level`` of :meth:`Design.estimator`; two rules over the same classes and levels
    are equal (so the estimators of one design share the levels they have looked up,
    :mod:`eqrec.estimators.intake`).

    Parameters
    ----------
    classes : ClassSet
        The design's classes.
    levels : numpy.ndarray
        The certified level of each class.
    """

    __slots__ = ("classes", "levels", "_key", "__weakref__")

    def __init__(self, classes, levels):
        self.classes, self.levels = classes, levels
        # the levels by value: a design's certificate gives them as a new array at each request
        self._key = np.asarray(levels, dtype=float).tobytes()

    def __call__(self, prefix: ArrivalPattern) -> float:
        depth = prefix.T
        return float(self.levels[self.classes.index(depth, prefix.available(depth - 1))])

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ClassLevels) and other.classes is self.classes and other._key == self._key

    def __hash__(self) -> int:
        return hash((id(self.classes), self._key))


@dataclass
class Mu1Free:
    """How the recovery level of a ``μ1``-free design was found (the μ1-free theorem,
    :mod:`eqrec.design.classes.mu1_min`).

    Parameters
    ----------
    route : {"global", "ipopt"}
        ``"global"``: the design at ``μ1,min`` in closed form (certified); ``"ipopt"``: IPOPT on problem (10)
        of the delayed-data paper (:mod:`eqrec.design.delay.ipopt`), ``μ1`` a variable.
    mu1_min : float or None, optional
        ``μ1,min`` attained by the recovered gains (global route).
    mu1_min_lower : float or None, optional
        A level proven infeasible below it (global route).
    binding : dict or None, optional
        The terminal class and row that set ``μ1,min`` (global route).
    lower_bound : float or None, optional
        The delay design's certified lower bound of ``J`` over every ``μ1`` (global route; ``nan`` when no level
        below ``μ1,min`` was solved).
    """

    route: str
    mu1_min: float | None = None
    mu1_min_lower: float | None = None
    binding: dict | None = None
    lower_bound: float | None = None


@dataclass
class Design:
    """A solved (and, once :func:`eqrec.bounds.certify.certify_design` ran, certified) design.

    What every design function returns (:func:`eqrec.design_prefix`,
    :func:`eqrec.design_time_based`, :func:`eqrec.design_delay`,
    :func:`eqrec.design_augmented`; :func:`eqrec.design_delay_global`
    wraps one): an estimator achieving equalized recovery (Definition 2 of
    the prefix-based paper, Definition 1 of the delayed-data paper) with
    recovery level ``μ1`` (``M1``) and intermediate level(s) ``μ2``
    (``M2``) over the horizon ``T``: for every ``‖ξ(0)‖∞ <= μ1`` and noise
    in the box, ``‖ξ(t)‖∞ <= μ2`` for ``t = 0..T`` and ``‖ξ(T)‖∞ <= μ1``.
    Designs are built by the design functions, not by hand; run one with
    :meth:`estimator`.

    Parameters
    ----------
    method : str
        ``"prefix"``, ``"time"``, ``"delay"``, ``"augmented"``, ...
    system : AffineSystem
        The system designed for.
    patterns : tuple of ArrivalPattern or str
        The designed arrival patterns (0/1 words are converted).
    T : int
        Horizon.
    mu1 : float
        Recovery level ``μ1``.
    mu2 : float
        Largest intermediate level (the LP optimum).
    schedule : GainSchedule or None
        The gains ``(F, u0)`` per pattern prefix (node gains), or ``None``
        for a class-engine design of a language too large to enumerate.
    solution : LPSolution
        The solver's record (status, objective, iterations, solve time).
    build_time : float
        Seconds spent building the optimisation problem.
    certificate : Certificate or None, optional
        The independent worst-case certificate of the node gains
        (:class:`eqrec.bounds.certify.Certificate`), attached by certification.
    extra : dict, optional
        Only a loaded design's (:func:`eqrec.load_design`): the file's entries that the design does not run on and
        that have no field below (``certified_mu2``, ``certified_terminal``, ``mu1_free``, ``L``, ``s0``, ``M``,
        ``nu``), as the file wrote them.  Every design computed here leaves it empty.
    levels : dict of str to float, optional
        Optional per-node levels ``μ2`` keyed by the node's prefix label.
    class_gains : ClassGains or None, optional
        Class engine: one gain ``K`` per (time, available data) class
        (:class:`eqrec.bounds.data_classes.ClassGains`), the estimator in class form.
        ``schedule`` (node gains) is then derived from them, or ``None`` for a
        language too large to enumerate.
    class_certificate : ClassCertificate or None, optional
        Class engine: the worst case of every class recomputed from the gains ``K``
        (:class:`eqrec.design.classes.gains.ClassCertificate`).
    state_weights : numpy.ndarray or None, optional
        Per-state weights ``w`` of a weighted design (the ``state_weights``
        keyword of the design entries): ``system`` is then the system in
        ``z = W x`` (:meth:`AffineSystem.scaled`), every level and certificate
        bounds ``max_i w_i |x_i − x̂_i|``, and :meth:`estimator` runs in the
        original state (:class:`eqrec.design.weighted.WeightedEstimator`).
    engine : {"tree", "classes"}, optional
        The engine that solved it: the prefix-tree LP (default; also the time-based, delay-tree and augmented
        designs) or the class engine (:mod:`eqrec.design.classes.engine`).
    cost : {"sum", "max"} or None, optional
        The delayed-data paper's cost the design minimised (:func:`eqrec.design.cost.paper_cost`), where counted.
    J : float or None, optional
        That cost at the stored levels (the delayed-data paper's ``J``, eq. (8)); ``None``: not counted.
    J_certified : float or None, optional
        ``J`` at the certified worst cases of the gains (:func:`eqrec.design.cost.certified_cost`).
    sequences, nodes : int or None, optional
        Distinct event sequences of the language and nodes of its prefix tree (delay and class-engine designs).
    classes : int or None, optional
        Class engine: the number of (time, available data) classes.
    class_levels : numpy.ndarray or None, optional
        Class engine: the level of every class, the LP's optimum raised to at least its certified worst case
        (:func:`eqrec.bounds.certify.certify_design`), shape ``(classes,)``.
    lp_rows, lp_cols, lp_nonzeros : int or None, optional
        Class engine: the size of its LP (one block LP, or the blocks together).
    total_time : float or None, optional
        Class engine: seconds from the call to the certified design.
    mu1_requested : float or None, optional
        The ``μ1`` asked for, where certification raised ``mu1`` to the fixed point the gains certify
        (:mod:`eqrec.bounds.certify`); ``None``: ``mu1`` is the request.
    level_raise : float or None, optional
        After certification: the largest relative raise of ``μ1`` or ``μ2`` it made (0 when none).
    language : tuple of str or None, optional
        Time-based and augmented designs: the words of the language the design covers.
    worst_case_word : str or None, optional
        Time-based and augmented designs: the language's worst-case word (bitwise AND), the word designed for.
    mu1_free : Mu1Free or None, optional
        A design at the smallest feasible ``μ1`` (``μ1`` free): how it was found; ``None``: ``μ1`` was given.
    augmented : AugmentedDetails or None, optional
        The augmented design's own record (:class:`eqrec.design.augmented.design.AugmentedDetails`: gains,
        ``L, s0, M, nu``, runtime mode, IPOPT's record).
    loaded_from : str or None, optional
        The file a loaded design was read from (:func:`eqrec.load_design`).

    Attributes
    ----------
    words : tuple of str
        Labels of the designed patterns.
    solve_time : float
        Seconds spent inside the solver.

    Examples
    --------
    >>> import eqrec
    >>> design = eqrec.design_prefix(eqrec.acc_system(), ["101111", "110111", "111011", "111101"], mu1=1.0)
    >>> design.method, design.T, design.mu1, design.certificate.mu2 <= design.mu2 * (1 + 1e-9)
    ('prefix', 6, 1.0, True)
    >>> design.words
    ('101111', '110111', '111011', '111101')
    """

    method: str
    system: AffineSystem
    patterns: tuple[ArrivalPattern, ...]
    T: int
    mu1: float
    mu2: float
    schedule: GainSchedule | None
    solution: LPSolution
    build_time: float
    certificate: "object | None" = None
    extra: dict = field(default_factory=dict)
    levels: dict[str, float] = field(default_factory=dict)
    class_gains: "object | None" = None
    class_certificate: "object | None" = None
    state_weights: "np.ndarray | None" = None
    engine: str = "tree"
    cost: str | None = None
    J: float | None = None
    J_certified: float | None = None
    sequences: int | None = None
    nodes: int | None = None
    classes: int | None = None
    class_levels: "np.ndarray | None" = None
    lp_rows: int | None = None
    lp_cols: int | None = None
    lp_nonzeros: int | None = None
    total_time: float | None = None
    mu1_requested: float | None = None
    level_raise: float | None = None
    language: tuple[str, ...] | None = None
    worst_case_word: str | None = None
    mu1_free: "Mu1Free | None" = None
    augmented: "object | None" = None
    loaded_from: str | None = None

    def __post_init__(self) -> None:
        self.patterns = tuple(as_pattern(p) for p in self.patterns)
        self.mu2 = float(self.mu2)

    @property
    def words(self) -> tuple[str, ...]:
        """Labels of the designed patterns (the 0/1 or delay words)."""
        return tuple(p.label for p in self.patterns)

    @property
    def solve_time(self) -> float:
        """Seconds spent inside the solver call (``solution.solve_time``)."""
        return self.solution.solve_time

    def estimator(self, periodic: bool = True, strict: bool = True,
                  tight: bool = True) -> "GuaranteedEstimator | WeightedEstimator":
        """The designed estimator, ready to run: ``reset(x̂0)``, then ``step(y, u) -> (x̂, bound)``.

        Class-engine designs run in class form (:class:`eqrec.estimators.causal.ClassEstimator`,
        one gain per (time, available data) class, no prefix tree) with the
        certified level of the class as the bound; other designs run their
        node gains (:class:`eqrec.estimators.causal.RecoveryEstimator`, eqs.
        (5), (7) of the prefix-based paper) with the node's (or the common)
        level.  ``μ1`` at each period end.  With ``periodic=True`` the
        estimator restarts its horizon every ``T`` steps (Section V of the
        prefix-based paper): the error is back within ``μ1`` at each period
        end, so the same gains apply again.  A weighted design
        (:attr:`state_weights`) returns a
        :class:`~eqrec.design.weighted.WeightedEstimator`: estimates in the
        original state, the bound on ``max_i w_i |x_i − x̂_i|``.

        Parameters
        ----------
        periodic : bool, optional
            Reuse the gains every ``T`` steps (the default) or stop after ``T``.
        strict : bool, optional
            ``True`` (default): arrivals outside the language raise
            :class:`InputError`.  ``False`` (class-engine designs): the
            estimator keeps a true bound outside the language and reports
            :attr:`GuaranteedEstimator.in_design` (:mod:`eqrec.estimators.guaranteed`).
        tight : bool, optional
            With ``strict=False``: ``True`` (default) reports, per state, the tighter of the designed estimate
            and the set-membership one that runs beside it (each with its exact bound; the designed levels stay
            guarantees); ``False`` reports the designed estimate alone (:mod:`eqrec.estimators.guaranteed`).

        Returns
        -------
        GuaranteedEstimator or WeightedEstimator
            Not yet started: call :meth:`GuaranteedEstimator.reset` first.

        Raises
        ------
        InputError
            If the design holds no gains to run.

        Examples
        --------
        >>> import numpy as np
        >>> import eqrec
        >>> design = eqrec.design_prefix(eqrec.acc_system(), ["101111", "110111", "111011", "111101"], mu1=1.0)
        >>> estimator = design.estimator().reset(np.zeros(3))
        >>> xhat, bound = estimator.step(np.array([1.0, 2.0]))  # y(0) arrives: its level plus the rounding allowance
        >>> xhat.shape, round(bound, 12)
        ((3,), 1.05)
        >>> xhat = estimator.update(None)  # y(1) is lost: the intermediate level
        >>> abs(estimator.bound - design.mu2) < 1e-9
        True
        """
        from eqrec.estimators.guaranteed import GuaranteedEstimator

        if self.class_gains is not None:
            gains, cert = self.class_gains, self.class_certificate
            bound_of = ClassLevels(gains.classes, cert.levels)
        else:
            if self.schedule is None:
                raise InputError("this design has no gains to run")
            gains = self.schedule
            bound_of = partial(node_level, self)
        estimator = GuaranteedEstimator(self.system, gains, bound_of, self.mu1, periodic=periodic, strict=strict,
                                       tight=tight)
        if self.state_weights is None:
            return estimator
        from eqrec.design.weighted import WeightedEstimator

        return WeightedEstimator(estimator, self.state_weights)

    def save(self, path: "str | os.PathLike") -> Path:
        """Write the design file that ``eqrec design ... --out path`` writes; :func:`eqrec.load_design` reads it back.

        The same record as the command line's (:func:`eqrec.design.report.design_json`): the system, ``T``,
        ``μ1``, ``μ2``, the certified values and the gains (class gains ``K`` and/or node gains ``(F, u0)``),
        written atomically (a reader never sees half a file).  Loading it certifies the gains again.

        Parameters
        ----------
        path : str or os.PathLike
            The JSON file to write (its folder must exist).

        Returns
        -------
        pathlib.Path
            The file written.

        Raises
        ------
        InputError
            A path that is not a str or path, a folder, a missing folder, or a file that cannot be written
            (field ``path``; nothing is left behind).

        Examples
        --------
        >>> import eqrec
        >>> design = eqrec.design_prefix(eqrec.acc_system(), ["101111", "110111"], mu1=1.0)
        >>> path = design.save("design.json")  # doctest: +SKIP
        >>> eqrec.load_design(path).mu2 == design.mu2  # doctest: +SKIP
        True
        """
        import json

        from eqrec.design.report import design_json
        from eqrec.io import write_text

        if not isinstance(path, (str, os.PathLike)):
            raise InputError(f"a design file is a path (str or pathlib.Path), got {type(path).__name__}",
                             field="path")
        file = Path(path)
        if file.is_dir():
            raise InputError("is a directory; give a file name for the JSON", str(file), "path")
        if not file.parent.is_dir():
            raise InputError(f"folder {file.parent} does not exist", str(file), "path")
        text = json.dumps(design_json(self), indent=2) + "\n"
        try:
            write_text(file, text)
        except OSError as exc:
            raise InputError(f"cannot write ({exc.strerror})", str(file), "path") from None
        return file
