"""Campaign files: the strict schema, and loading one together with the problem file it varies.

A campaign file names a problem file and what varies over its runs (keys of the ``lpmpc`` single case)::

    name: lpmpc-dispersed
    problem: ../feng2018_lpmpc_single.yaml      # relative to the campaign file
    set: ["lqr.r=[0.01]"]                       # --set overrides applied to every run
    grid:                                       # full factorial over the axes, the last axis fastest
      - {key: lpmpc.nodes, values: [8, 10, 12]}
      - {keys: [lpmpc.check_interval_s, simulation.dt_s], values: [[2.0, 0.01], [1.0, 0.005]]}  # linked keys
    dispersions:                                # drawn per Monte Carlo sample, in this order
      - {key: initial_error.euler_deg.0, distribution: normal, mean: 0.0, std: 3.16}  # mean: default the file's
      - {key: disturbance.torque_std_Nm, distribution: uniform, low: 0.02, high: 0.08}
    samples: 50                                 # Monte Carlo samples per grid point
    seed: 2018                                  # the campaign seed
    seed_key: simulation.seed                   # problem key that receives each sample's own seed
    figures: [lpmpc_energy_N2m2s, runs.1.energy_N2m2s]

Keys are the dotted paths of ``convexguid solve --set``. ``problem`` may also name a problem module (a ``.py`` file
whose ``build(...)`` returns a :class:`convexguid.ocp.Problem`): its keys are then ``build``'s parameters, a
dispersion's default mean is the parameter's default, and its figures are those of family ``ocp``. A figure is a
dotted path into the solve's summary (:meth:`convexguid.solution.Solution.summary`), whose first part is a summary
key. Every problem is a :class:`~convexguid.errors.SpecError` whose one line names the campaign file, the key and
the value; the problem file and each grid point are validated here, before anything runs.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass
from itertools import product
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import Field, ValidationError, model_validator

from convexguid.campaign.plan import override
from convexguid.errors import SpecError
from convexguid.families import Family, get_family
from convexguid.problem_files import parse_problem
from convexguid.spec.common import NonEmptyStr, PositiveFloat, SpecModel, spec_error
from convexguid.spec.loader import MISSING, apply_overrides, describe_validation_error, read_yaml_mapping, value_at

DottedKey = Annotated[str, Field(pattern=r"^[A-Za-z0-9_]+(\.[A-Za-z0-9_]+)*$")]
"""A key path as for ``--set``: names and list indices joined by dots."""

SUMMARY_KEYS = ("objective", "iterations", "num_variables", "num_equality_constraints",
                "num_inequality_constraints", "wall_time_s", "timing", "verification", "repair_rounds", "kkt")
"""Numeric (or nested) keys every summary has besides the family's figures; a figure path may start with one."""

PROSE_KEYS = ("description", "notes", "reference")
"""Keys of a problem file that document it and do not change a solve (left out of the campaign's fingerprint)."""

RESERVED_COLUMNS = ("run_id", "sample", "seed", "status", "message", "objective", "verified", "wall_time_s",
                    "overrides")
"""Columns of the results table that are not a varied key or a figure."""


class GridAxis(SpecModel):
    """One axis of the grid: ``key`` with its ``values``, or linked ``keys`` whose values move together (each
    value a list with one entry per key)."""

    key: DottedKey | None = None
    keys: Annotated[list[DottedKey], Field(min_length=2)] | None = None
    values: list[Any]

    @model_validator(mode="after")
    def _one_form(self) -> GridAxis:
        if (self.key is None) == (self.keys is None):
            raise spec_error("give either key or keys", "key: one dotted key; keys: linked keys moving together",
                             key=("key",), value=self.key if self.key is not None else self.keys)
        if self.keys is not None:
            for i, value in enumerate(self.values):
                if not isinstance(value, list) or len(value) != len(self.keys):
                    raise spec_error(f"expected a list of {len(self.keys)} values, one per key of {{here}}keys",
                                     f"give values as [[{', '.join(['v'] * len(self.keys))}], ...]",
                                     key=("values", i), value=value)
        return self

    @property
    def names(self) -> tuple[str, ...]:
        """The keys this axis sets."""
        return (self.key,) if self.key is not None else tuple(self.keys)

    def points(self) -> list[tuple[Any, ...]]:
        """One tuple of values (one per key of :attr:`names`) per value of the axis."""
        return [(v,) if self.key is not None else tuple(v) for v in self.values]


class NormalDispersion(SpecModel):
    """``key`` drawn from a normal distribution; ``mean`` defaults to the problem file's value."""

    key: DottedKey
    distribution: Literal["normal"]
    std: PositiveFloat
    mean: float | None = None

    def draw(self, rng, nominal: float) -> float:
        """One value from the generator ``rng``; ``nominal`` is the problem file's value."""
        return float(rng.normal(self.centre(nominal), self.std))

    def centre(self, nominal: float) -> float:
        """The mean (the problem file's value ``nominal`` unless the campaign gives one)."""
        return nominal if self.mean is None else self.mean


class UniformDispersion(SpecModel):
    """``key`` drawn uniformly from ``[low, high)``."""

    key: DottedKey
    distribution: Literal["uniform"]
    low: float
    high: float

    @model_validator(mode="after")
    def _ordered(self) -> UniformDispersion:
        if not self.high > self.low:
            raise spec_error("must be greater than {here}low = " + repr(self.low), "give low < high",
                             key=("high",), value=self.high)
        return self

    def draw(self, rng, nominal: float) -> float:
        """One value from the generator ``rng`` (``nominal`` unused: the bounds are absolute)."""
        return float(rng.uniform(self.low, self.high))

    def centre(self, nominal: float) -> float:
        """The middle of the interval."""
        return 0.5 * (self.low + self.high)


Dispersion = Annotated[NormalDispersion | UniformDispersion, Field(discriminator="distribution")]


class CampaignSpec(SpecModel):
    """A campaign file (see the module docstring)."""

    name: NonEmptyStr
    description: str = ""
    problem: NonEmptyStr
    set: list[str] = Field(default_factory=list)
    grid: list[GridAxis] = Field(default_factory=list)
    dispersions: list[Dispersion] = Field(default_factory=list)
    samples: Annotated[int, Field(ge=0)] | None = None
    seed: Annotated[int, Field(ge=0)] | None = None
    seed_key: DottedKey | None = None
    figures: list[DottedKey] = Field(default_factory=list)

    @model_validator(mode="after")
    def _consistent(self) -> CampaignSpec:
        random = bool(self.dispersions) or self.seed_key is not None
        if not random and not self.grid:
            raise spec_error("nothing varies", "give a grid, dispersions or a seed_key", key=("grid",), value=[])
        if random:
            for name in ("samples", "seed"):
                if getattr(self, name) is None:
                    raise spec_error("missing: required with dispersions or a seed_key",
                                     f"give {name}: an integer >= 0", key=(name,), value=None)
        elif self.samples is not None:
            raise spec_error("samples without dispersions or a seed_key would repeat the same run",
                             "remove samples, or add dispersions or a seed_key", key=("samples",),
                             value=self.samples)
        seen: dict[str, str] = {}
        owners = [(f"set.{i}", o.partition("=")[0].strip()) for i, o in enumerate(self.set)]
        owners += [(f"grid.{i}", k) for i, axis in enumerate(self.grid) for k in axis.names]
        owners += [(f"dispersions.{i}.key", d.key) for i, d in enumerate(self.dispersions)]
        owners += [("seed_key", self.seed_key)] if self.seed_key is not None else []
        for where, key in owners:
            if key in RESERVED_COLUMNS and not where.startswith("set."):
                raise spec_error("a varied key cannot share its name with a column of the results table",
                                 f"columns {', '.join(RESERVED_COLUMNS)} are taken; set this key in the problem "
                                 "file (or in set) and make one campaign per value", key=tuple(where.split(".")),
                                 value=key)
            if key in seen:
                raise spec_error(f"key already varied or set by {seen[key]}", "vary or set each key once",
                                 key=tuple(where.split(".")), value=key)
            seen[key] = where
        for i, figure in enumerate(self.figures):
            if figure in RESERVED_COLUMNS or figure in seen or figure in self.figures[:i]:
                raise spec_error("already a column of the results table", "name each figure once, and not "
                                 f"one of {', '.join(RESERVED_COLUMNS)} or a varied key",
                                 key=("figures", i), value=figure)
        return self

    @property
    def varied_keys(self) -> tuple[str, ...]:
        """Grid keys, then dispersed keys: the varied-value columns of the results table."""
        return tuple(k for axis in self.grid for k in axis.names) + tuple(d.key for d in self.dispersions)

    @property
    def random(self) -> bool:
        """Whether runs draw from the campaign seed (dispersions or a seed_key)."""
        return bool(self.dispersions) or self.seed_key is not None


@dataclass(frozen=True)
class ModuleFamily:
    """What a campaign reads of a family, for a problem module (:mod:`convexguid.ocp`)."""

    figures: type
    name: str = "ocp"
    simulated: bool = False


@dataclass(frozen=True)
class Campaign:
    """A validated campaign with the data of its problem file.

    ``problem_data`` is the problem file as read (before any override); ``problem_source`` its absolute path,
    which workers use in messages and to find files the problem names relative to itself (e.g. an lpmpc
    nominal). ``nominal`` is each dispersed key's value in the problem (after ``set``), the default mean.
    ``fingerprint`` identifies what defines the runs: every campaign key but the name and description, and the
    problem file's data but its prose and paper reference (:data:`PROSE_KEYS`); a results table keeps it.
    """

    spec: CampaignSpec
    source: str
    problem_source: str
    problem_data: dict[str, Any]
    family: Family | ModuleFamily
    nominal: dict[str, float]
    fingerprint: str

    @property
    def module(self) -> bool:
        """Whether the problem is a module stated in Python (runs build it) rather than a problem file."""
        return self.problem_source.endswith(".py")

    @property
    def command(self) -> str:
        """``solve`` or ``simulate``: the convexguid command that replays one run."""
        return "simulate" if self.family.simulated else "solve"


def load_campaign(path: str | Path) -> Campaign:
    """Read and validate the campaign file ``path`` and the problem file it names.

    Raises
    ------
    SpecError
        One line naming the file, the key and the value: a campaign key that is unknown or invalid, a problem
        file that does not load, a dispersion on a key that is not a number, a grid point that gives an invalid
        problem, a figure that is no summary key, or zero runs.
    """
    source = str(path)
    data = read_yaml_mapping(path, "a campaign file is a mapping of keys such as name, problem, grid, figures")
    try:
        spec = CampaignSpec.model_validate(data)
    except ValidationError as exc:
        raise SpecError(f"{source}: {describe_validation_error(exc, CampaignSpec)}") from None
    _check_run_count(spec, source)
    problem_path = (Path(path).parent / spec.problem).resolve()
    if not problem_path.is_file():
        raise SpecError(f"{source}: problem: no such file (got {spec.problem!r}, looked for {problem_path}); "
                        "give the problem file's path relative to the campaign file")
    problem_source = str(problem_path)
    if problem_path.suffix == ".py":
        return _load_module_campaign(spec, source, problem_path)
    problem_data = read_yaml_mapping(problem_path, "a problem file is a mapping of keys such as name, family")
    base = apply_overrides(problem_data, spec.set, problem_source)
    family = get_family(parse_problem(base, problem_source).family)
    _check_figures(spec, family, source)
    nominal = {d.key: _numeric_value(base, d.key, f"dispersions.{i}.key", source, problem_source)
               for i, d in enumerate(spec.dispersions)}
    _check_grid_points(spec, nominal, source,
                       lambda overrides: parse_problem(apply_overrides(base, overrides, problem_source),
                                                       problem_source))
    problem_keys = {k: v for k, v in problem_data.items() if k not in PROSE_KEYS}
    return Campaign(spec, source, problem_source, problem_data, family, nominal, _fingerprint(spec, problem_keys))


def _fingerprint(spec: CampaignSpec, problem: Any) -> str:
    campaign_keys = spec.model_dump(mode="json", exclude={"name", "description"})
    return hashlib.sha256(json.dumps({"campaign": campaign_keys, "problem": problem},
                                     sort_keys=True, default=str).encode()).hexdigest()


def _load_module_campaign(spec: CampaignSpec, source: str, path: Path) -> Campaign:
    """A campaign over a problem module: keys are ``build``'s parameters, checked by building the problem."""
    # the CasADi layer loads only for a campaign that names a module
    from convexguid.ocp.module import load_module_problem, module_parameters
    from convexguid.ocp.solve import OcpFigures

    try:
        load_module_problem(path, spec.set)
        defaults = module_parameters(path)
    except SpecError as exc:
        raise SpecError(f"{source}: problem: {exc}") from None
    family = ModuleFamily(OcpFigures)
    _check_figures(spec, family, source)
    given = {**defaults, **{o.partition("=")[0].strip(): yaml.safe_load(o.partition("=")[2]) for o in spec.set}}
    nominal = {}
    for i, d in enumerate(spec.dispersions):
        value = given.get(d.key, MISSING)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SpecError(f"{source}: dispersions.{i}.key: {d.key} is not a build() parameter with a number for "
                            f"its default in {path} (got {value if value is not MISSING else 'no such parameter'!r});"
                            f" build()'s parameters: {', '.join(defaults) or 'none'}")
        nominal[d.key] = float(value)
    _check_grid_points(spec, nominal, source, lambda overrides: load_module_problem(path, overrides))
    return Campaign(spec, source, str(path), {}, family, nominal, _fingerprint(spec, path.read_text()))


def _check_run_count(spec: CampaignSpec, source: str) -> None:
    for i, axis in enumerate(spec.grid):
        if not axis.values:
            raise SpecError(f"{source}: grid.{i}.values: gives zero runs (got []); give at least one value")
    if spec.random and spec.samples == 0:
        raise SpecError(f"{source}: samples: gives zero runs (got 0); give at least one sample")


def _check_figures(spec: CampaignSpec, family: Family, source: str) -> None:
    valid = SUMMARY_KEYS + family.figures.names()
    for i, figure in enumerate(spec.figures):
        if figure.split(".")[0] not in valid:
            raise SpecError(f"{source}: figures.{i}: not a summary key of family {family.name} (got {figure!r}); "
                            f"a figure is a dotted path starting with one of: {', '.join(valid)}")


def _numeric_value(data: dict[str, Any], key: str, where: str, source: str, problem_source: str) -> float:
    """The number at ``key`` in the problem data; a :class:`SpecError` if there is none."""
    node = value_at(data, key)
    if node is MISSING:
        raise SpecError(f"{source}: {where}: no such key in {problem_source} (got {key!r}); a dispersion "
                        "varies a number the problem file gives (list items by index, e.g. euler_deg.0)")
    if isinstance(node, bool) or not isinstance(node, (int, float)):
        example = f"; e.g. {key}.0" if isinstance(node, list) else ""
        raise SpecError(f"{source}: {where}: {key} is not a number in {problem_source} (got {node!r}); "
                        f"disperse a key whose value is one number{example}")
    return float(node)


def _check_grid_points(spec: CampaignSpec, nominal: dict[str, float], source: str,
                       validate: Callable[[list[str]], Any]) -> None:
    """Validate the problem at every grid point (dispersed keys at their centre, the seed key at 0) by
    ``validate(overrides)``, which raises :class:`SpecError` for an invalid problem."""
    fixed = [override(d.key, d.centre(nominal[d.key])) for d in spec.dispersions]
    fixed += [override(spec.seed_key, 0)] if spec.seed_key is not None else []
    axes = [[(i, axis.names, point) for point in axis.points()] for i, axis in enumerate(spec.grid)]
    for combination in product(*axes):
        overrides = [override(k, v) for _, names, point in combination for k, v in zip(names, point, strict=True)]
        try:
            validate(overrides + fixed)
        except SpecError as exc:
            where = ", ".join(f"grid.{i}" for i, _, _ in combination) or "dispersions"
            raise SpecError(f"{source}: {where}: the problem is invalid at {' '.join(overrides + fixed)} "
                            f"({exc})") from None
