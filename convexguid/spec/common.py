"""Building blocks shared by every problem family.

Every model is a frozen pydantic model that rejects unknown keys and does no
type coercion (a string where a number is expected is an error; integers are
accepted for floats). YAML keys carry their unit (``tf_s``, ``half_angle_deg``);
read-only properties give the SI values (``half_angle_rad``, ``inertia_matrix``).

Validators report problems with :func:`spec_error`, which carries what is wrong,
what would be valid, and optionally a key path below the failing location and the
offending value; :mod:`convexguid.spec.loader` turns these into one-line
:class:`~convexguid.errors.SpecError` messages.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, Any, Literal, NamedTuple

import numpy as np
from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PlainValidator,
    PrivateAttr,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from convexguid.backends import check_backend_name
from convexguid.errors import BackendError, SpecError, value_text
from convexguid.spec.numbers import as_declared

SPEC_CONFIG = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False, defer_build=True)
"""Model configuration of every spec model (unknown keys, coercion and inf/nan are errors). A model's validator is
built when it first validates (``defer_build``): a command loads one family's models, not all five."""

SPEC_ERROR_TYPE = "convexguid_spec"
"""pydantic error type raised by :func:`spec_error`."""

_NO_VALUE = object()


def spec_error(problem: str, hint: str, *, key: Sequence[str | int] = (), value: Any = _NO_VALUE
               ) -> PydanticCustomError:
    """Build a validation error that the loader renders as ``path: problem (got value); hint``.

    Parameters
    ----------
    problem : str
        What is wrong. The token ``{here}`` is replaced by the dotted path of the model that
        raised the error followed by a dot (empty at the top level), so cross-field checks can
        name sibling keys: ``"must be greater than {here}t0_s = 0.0"``.
    hint : str
        What would be valid.
    key : sequence of str or int, optional
        Key path, below the location pydantic reports, of the offending entry.
    value : object, optional
        The offending value; by default the input pydantic reports.

    Returns
    -------
    pydantic_core.PydanticCustomError
        To be raised from a validator.
    """
    ctx: dict[str, Any] = {"problem": problem, "hint": hint, "key": tuple(key)}
    if value is not _NO_VALUE:
        ctx["value"] = value
    return PydanticCustomError(SPEC_ERROR_TYPE, "{problem}; {hint}", ctx)


def readonly(array: np.ndarray) -> np.ndarray:
    """Return ``array`` marked read-only."""
    array.setflags(write=False)
    return array


def _is_number(x: object) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _numbers(v: object, length: int, hint: str, key: tuple[int, ...] = ()) -> tuple[float, ...]:
    """Check that ``v`` (at ``key`` below the validated field) is a list of ``length`` finite numbers."""
    if not isinstance(v, (list, tuple)):
        raise spec_error(f"expected a list of {length} numbers", hint, key=key, value=v)
    if len(v) != length:
        raise spec_error(f"has {len(v)} entries instead of {length}", hint, key=key, value=v)
    for i, x in enumerate(v):
        if not _is_number(x):
            raise spec_error("not a number", hint, key=(*key, i), value=x)
        if not math.isfinite(x):
            raise spec_error("not a finite number", hint, key=(*key, i), value=x)
    return tuple(float(x) for x in v)


def _vector3(v: object) -> tuple[float, float, float]:
    return _numbers(v, 3, "give a list of 3 finite numbers")  # type: ignore[return-value]


def _direction3(v: object) -> tuple[float, float, float]:
    hint = "give a nonzero 3-vector"
    vec = _numbers(v, 3, hint)
    if math.sqrt(sum(x * x for x in vec)) <= 1e-12:
        raise spec_error("zero-length direction vector", hint)
    return vec  # type: ignore[return-value]


Vector3 = Annotated[tuple[float, float, float], PlainValidator(_vector3)]
"""Three finite numbers (a YAML list), stored as a tuple of floats."""

Direction3 = Annotated[tuple[float, float, float], PlainValidator(_direction3)]
"""A :data:`Vector3` of norm greater than 1e-12 (not normalised; see the ``*_unit`` properties)."""

QUATERNION_NORM_TOL = 0.01
"""Largest accepted :math:`|\\,\\|q\\| - 1|` of a YAML quaternion; within it the quaternion is normalised
(papers print 3-4 digits, e.g. ``[0, 0, 0.707, 0.707]``), beyond it rejected as a typo."""


def _unit_quaternion(v: object) -> tuple[float, float, float, float]:
    """Four finite numbers whose norm is within :data:`QUATERNION_NORM_TOL` of 1, returned normalised."""
    hint = (f"give a unit quaternion [x, y, z, w] (scalar last; a norm within {QUATERNION_NORM_TOL:g} of 1 is "
            "normalised)")
    q = _numbers(v, 4, hint)
    norm = math.sqrt(sum(x * x for x in q))
    if abs(norm - 1.0) > QUATERNION_NORM_TOL:
        raise spec_error(f"quaternion norm is {norm:.6g}, not 1", hint)
    return tuple(x / norm for x in q)  # type: ignore[return-value]


UnitQuaternion = Annotated[tuple[float, float, float, float], PlainValidator(_unit_quaternion)]
"""Scalar-last unit quaternion ``[x, y, z, w]`` (body relative to inertial), normalised on input."""

def _torque_box(v: object) -> float | tuple[float, float, float]:
    """One positive number (every body axis) or a list of 3 positive numbers (x, y, z), kept as given."""
    hint = "give a positive number (every axis) or a list of 3 positive numbers [x, y, z]"
    if isinstance(v, (list, tuple)):
        box = _numbers(v, 3, hint)
        for i, x in enumerate(box):
            if x <= 0.0:
                raise spec_error("must be positive", hint, key=(i,), value=v[i])
        return box  # type: ignore[return-value]
    if not _is_number(v):
        raise spec_error("not a number or a list of 3 numbers", hint)
    if not math.isfinite(v):  # type: ignore[arg-type]
        raise spec_error("not a finite number", hint)
    if v <= 0.0:  # type: ignore[operator]
        raise spec_error("must be greater than 0", hint)
    return float(v)  # type: ignore[arg-type]


TorqueBox = Annotated[float | tuple[float, float, float], PlainValidator(_torque_box)]
"""Per-axis bound :math:`|u_i| \\le u_{max,i}`: one positive number for every axis, or 3 (x, y, z); see
:func:`torque_box_vector`."""


def torque_box_vector(box: float | Sequence[float]) -> np.ndarray:
    """A :data:`TorqueBox` as a read-only length-3 array (a single number repeated on every axis)."""
    return readonly(np.broadcast_to(np.asarray(box, dtype=float), (3,)).copy())


PositiveFloat = Annotated[float, Field(gt=0)]
NonNegativeFloat = Annotated[float, Field(ge=0)]
NonEmptyStr = Annotated[str, Field(min_length=1)]


def _inertia(v: object) -> tuple[tuple[float, float, float], ...]:
    """Validate 3 principal moments or a symmetric positive definite 3x3 matrix (kg m^2)."""
    hint = "give 3 positive principal moments or a symmetric positive definite 3x3 matrix"
    if isinstance(v, (list, tuple)) and v and all(isinstance(row, (list, tuple)) for row in v):
        if len(v) != 3:
            raise spec_error(f"matrix has {len(v)} rows", hint)
        rows = [_numbers(row, 3, hint, key=(i,)) for i, row in enumerate(v)]
        matrix = np.array(rows)
        scale = float(np.max(np.abs(matrix)))
        if float(np.max(np.abs(matrix - matrix.T))) > 1e-9 * scale:
            raise spec_error("inertia matrix is not symmetric", hint)
        matrix = 0.5 * (matrix + matrix.T)
    else:
        moments = _numbers(v, 3, hint)
        for i, moment in enumerate(moments):
            if moment <= 0.0:
                raise spec_error("principal moment of inertia must be positive", hint, key=(i,),
                                 value=v[i])  # type: ignore[index]
        matrix = np.diag(moments)
    if float(np.linalg.eigvalsh(matrix)[0]) <= 0.0:
        raise spec_error("inertia matrix is not positive definite", hint)
    return tuple(tuple(float(x) for x in row) for row in matrix)


InertiaMatrix = Annotated[tuple[tuple[float, float, float], ...], PlainValidator(_inertia)]
"""Inertia in kg m^2: 3 principal moments or a 3x3 matrix in YAML, stored as a 3x3 tuple."""


class SpecModel(BaseModel):
    """Base of every spec model: frozen, strict, unknown keys rejected.

    A number the YAML reader took from scientific notation (``1e3``) reaches a string key as its text and an
    integer key as an int (:func:`~convexguid.spec.numbers.as_declared`). Assigning to a field raises a one-line
    :class:`~convexguid.errors.SpecError`: a spec is changed by loading it again with overrides.
    """

    model_config = SPEC_CONFIG

    @model_validator(mode="before")
    @classmethod
    def _numbers_as_declared(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        fields = cls.model_fields
        return {key: as_declared(fields[key].annotation, value) if key in fields else value
                for key, value in data.items()}

    def __setattr__(self, name: str, value: Any) -> None:
        if name.startswith("_"):  # private attributes (the loader's ``_source``)
            super().__setattr__(name, value)
            return
        raise SpecError(f"{type(self).__name__}.{name}: a problem spec is read-only (got {value_text(value)}); "
                        "load the problem again with an override instead, e.g. "
                        "convexguid.load_problem(path, ['key.path=value'])")

    def __delattr__(self, name: str) -> None:
        raise SpecError(f"{type(self).__name__}.{name}: a problem spec is read-only; keys cannot be removed")


class TimeInterval(SpecModel):
    """A maneuver from ``t0_s`` to ``tf_s`` (s, ``tf_s > t0_s``); boundary sections of the families extend it."""

    t0_s: float = 0.0
    tf_s: float

    @model_validator(mode="after")
    def _tf_after_t0(self) -> TimeInterval:
        if self.tf_s <= self.t0_s:
            raise spec_error(f"must be greater than {{here}}t0_s = {self.t0_s!r}",
                             "give a final time after the initial time", key=("tf_s",), value=self.tf_s)
        return self

    @property
    def duration_s(self) -> float:
        """Maneuver duration ``tf_s - t0_s``, s."""
        return self.tf_s - self.t0_s


def _as_tuple(v: object) -> tuple[object, ...]:
    if not isinstance(v, (list, tuple)):
        raise spec_error("expected a list", "give a YAML list (possibly empty) of mappings")
    return tuple(v)


def _unique_names(items: tuple) -> tuple:
    seen: set[str] = set()
    for i, item in enumerate(items):
        if item.name in seen:
            raise spec_error("duplicate name", "give every entry a unique name", key=(i, "name"), value=item.name)
        seen.add(item.name)
    return items


def named_list(model: type) -> object:
    """Type of a YAML list of ``model`` mappings with unique ``name`` keys, stored as a tuple."""
    return Annotated[tuple[model, ...], BeforeValidator(_as_tuple), AfterValidator(_unique_names)]


class SolverSettings(SpecModel):
    """Settings of the sequential convex programming loop and its convex backend.

    Attributes
    ----------
    backend : str
        Convex solver name (see :mod:`convexguid.backends`); ``auto`` (the default) picks the
        subproblem's form and solver from the program (:mod:`convexguid.scp.choice`).
    max_iterations : int
        Maximum number of SCP iterations.
    tolerance : float
        Step and predicted-decrease tolerance of the SCP loop (scaled variables; decrease relative to the merit).
    kkt_tolerance : float
        Tolerance of the KKT residuals (stationarity and complementarity relative to the objective), the stop that
        proves optimality (:mod:`convexguid.scp.optimality`).
    second_order : bool
        Newton's end game on the subproblems' working set (:mod:`convexguid.scp.endgame`); ``false`` leaves the
        first-order SCP alone.
    trust_region : float
        Initial trust-region radius.
    penalty : float
        Weight of the exact penalty on constraint violations.
    verbose : bool
        Print the iteration table.
    """

    backend: str = "auto"
    max_iterations: Annotated[int, Field(ge=1)] = 50
    tolerance: PositiveFloat = 1e-6
    kkt_tolerance: PositiveFloat = 1e-6
    second_order: bool = True
    trust_region: PositiveFloat = 0.5
    penalty: PositiveFloat = 1e3
    verbose: bool = True

    @field_validator("backend")
    @classmethod
    def _known_backend(cls, name: str) -> str:
        try:
            check_backend_name(name)
        except BackendError as exc:
            _, _, installed = str(exc).partition("; ")
            raise spec_error("unknown backend", installed or str(exc)) from None
        return name


class VerificationSettings(SpecModel):
    """Settings of the dense re-propagation that checks a planned trajectory.

    Attributes
    ----------
    grid_points : int
        Number of points of the dense time grid.
    rtol, atol : float
        Relative and absolute tolerances of the scipy integrator.
    final_attitude_tol_rad : float
        Allowed final attitude error, rad.
    final_rate_tol_radps : float
        Allowed final angular-rate error, rad/s.
    constraint_tol : float
        Relative slack allowed on path constraints.
    """

    grid_points: Annotated[int, Field(ge=100)] = 2001
    rtol: PositiveFloat = 1e-10
    atol: PositiveFloat = 1e-12
    final_attitude_tol_rad: PositiveFloat = 1e-3
    final_rate_tol_radps: PositiveFloat = 1e-4
    constraint_tol: NonNegativeFloat = 1e-6


class ComparisonEntry(SpecModel):
    """The row a case contributes to one of the validation report's cross-method tables.

    Cases whose ``reference.comparison`` names the same ``table`` are rendered side by side, one row each,
    in the order the validation runs them (see :mod:`convexguid.validation.comparisons`, which lists the tables,
    their columns and their roles).

    Attributes
    ----------
    table : str
        Id of the table (e.g. ``multicone``, ``forbidden_attitude``); checked by the validation runner.
    label : str
        Row label (the ``method`` column).
    role : {"baseline", "min_time", "min_energy", "tracked"} or None
        What the row stands for in the sentences under the table: ``baseline`` the method the others are
        set against (e.g. the paper's own planner or controller), ``min_time`` / ``min_energy`` the
        minimum-time / minimum-energy plan, ``tracked`` a plan flown closed loop by a tracking law. At most
        one row of a table per role.
    figures : dict of str to str or None
        Summary figures filling the table's columns where the column's default figure does not apply,
        by column id (e.g. ``{maneuver_time: maneuver_time_01deg_s}`` for a simulated controller).
    """

    table: NonEmptyStr
    label: NonEmptyStr
    role: Literal["baseline", "min_time", "min_energy", "tracked"] | None = None
    figures: dict[str, NonEmptyStr] | None = None


class ResultLink(SpecModel):
    """An input taken from another case's result: figure ``figure`` of the summary of problem ``problem``.

    The commands resolve it (:mod:`convexguid.validation.links`: they solve ``problem`` first, ``validate`` among
    its cases and ``solve``, ``simulate``, ``bench`` from the problem file of that name beside this one, and
    pass the figure in as an override); the Python API refuses a problem with an unresolved link.

    Attributes
    ----------
    problem : str
        ``name`` of the problem whose result gives the value.
    figure : str
        Key of that result's summary (e.g. ``maneuver_time_01deg_s``).
    """

    problem: NonEmptyStr
    figure: NonEmptyStr


class InputLink(NamedTuple):
    """An unresolved :class:`ResultLink` of a problem: ``link`` (at ``link_key``) gives the value of ``key``."""

    key: str
    link_key: str
    link: ResultLink


class Reference(SpecModel):
    """Published values a problem reproduces, and the tolerances the validation applies.

    Attributes
    ----------
    citation : str
        Full citation of the paper.
    table : str
        Table or figure the values come from.
    values : dict of str to float
        Published values by quantity name (keys of the summary JSON, e.g. ``objective``).
    rel_tol : float
        Default relative tolerance.
    tolerances : dict of str to float or None
        Per-quantity relative tolerances overriding ``rel_tol``.
    max_values : dict of str to float or None
        Quantities that must not exceed the given number (e.g. ``iterations``).
    notes : str or None
        Free text.
    comparison : ComparisonEntry or None
        The case's row in a cross-method table of the report (``{table: <id>, label: <row label>}``, optionally
        ``role`` and ``figures``; see :class:`ComparisonEntry`).
    """

    citation: NonEmptyStr
    table: NonEmptyStr
    values: dict[str, float]
    rel_tol: PositiveFloat = 1e-3
    tolerances: dict[str, NonNegativeFloat] | None = None
    max_values: dict[str, float] | None = None
    notes: str | None = None
    comparison: ComparisonEntry | None = None

    def tolerance_for(self, quantity: str) -> float:
        """Relative tolerance applied to ``quantity``."""
        return (self.tolerances or {}).get(quantity, self.rel_tol)


class ProblemBase(SpecModel):
    """Keys common to every problem file; each family subclasses it.

    Attributes
    ----------
    name : str
        Problem name (used in reports and the summary JSON).
    family : str
        Problem family; selects the model class (see :mod:`convexguid.families`).
    method : str
        Solution method.
    description, notes : str or None
        Free text (``notes`` says e.g. which parameters the paper does not give).
    """

    name: NonEmptyStr
    family: str
    method: Literal["scp"] = "scp"
    description: str | None = None
    notes: str | None = None
    _source: str = PrivateAttr(default="<dict>")
    _data: dict[str, Any] = PrivateAttr(default_factory=dict)

    @property
    def source(self) -> str:
        """File the problem was read from, ``"<dict>"`` when built from Python."""
        return self._source

    def input_links(self) -> tuple[InputLink, ...]:
        """Inputs still to be taken from other cases' results (e.g. ``boundary.tf_from``); none by default.

        The commands resolve each (:mod:`convexguid.validation.links`) by solving ``link.problem`` first and
        loading this problem again with the overrides ``<link_key>=null`` and ``<key>=<figure value>``.
        """
        return ()
