"""The results table of a campaign: one Parquet row per run, each run on disk as soon as it arrives.

Why Parquet (pyarrow) and not CSV: the columns are typed (a missing figure is a null float, not an empty string
to guess about; the overrides are a list of strings, not text to quote and split), and any dataframe library
reads the file directly. Parquet cannot be appended to in place, so each arriving run is written as its own
one-row part file ``results.parts/run-<id>.parquet`` (to a temporary name, then renamed: a part is whole or
absent, whatever interrupts the campaign), and the parts are merged into ``results.parquet`` (again through a
temporary file and a rename) when a session ends, however it ends, and when a resumed session starts. A run is
finished once its row exists, in the file or in a part; rows are unique by run id.

The file's schema metadata carries the campaign's fingerprint (its file and its problem file's content), so a
directory is only ever resumed by the campaign that wrote it.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pyarrow as pa
import pyarrow.parquet as pq

from convexguid.campaign.plan import yaml_text
from convexguid.errors import SpecError
from convexguid.outputs import atomic_file

if TYPE_CHECKING:
    from convexguid.campaign.definition import Campaign
    from convexguid.campaign.plan import Run

TABLE_FILE = "results.parquet"
PARTS_DIR = "results.parts"
_METADATA_KEY = b"convexguid.campaign"


def is_ok(row: dict[str, Any]) -> bool:
    """A run that converged and passed its verification (anything else counts as a failure)."""
    return row["status"] == "converged" and row["verified"] is True


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def numeric_keys(runs: Sequence[Run], keys: Sequence[str]) -> set[str]:
    """The varied keys whose values are numbers in every run (float columns; the others hold YAML text)."""
    return {k for k in keys if all(_is_number(run.values[k]) for run in runs)}


def table_schema(campaign: Campaign, runs: Sequence[Run]) -> pa.Schema:
    """Columns: run id, sample, the varied keys, seed, status, message, objective, verified, wall time, the
    figures, the replay overrides; the campaign's name and fingerprint in the metadata."""
    spec = campaign.spec
    numeric = numeric_keys(runs, spec.varied_keys)
    fields = [pa.field("run_id", pa.int64(), nullable=False), pa.field("sample", pa.int64(), nullable=False)]
    fields += [pa.field(k, pa.float64() if k in numeric else pa.string()) for k in spec.varied_keys]
    fields += [pa.field("seed", pa.int64()), pa.field("status", pa.string()), pa.field("message", pa.string()),
               pa.field("objective", pa.float64()), pa.field("verified", pa.bool_()),
               pa.field("wall_time_s", pa.float64())]
    fields += [pa.field(f, pa.float64()) for f in spec.figures]
    fields.append(pa.field("overrides", pa.list_(pa.string())))
    metadata = {"name": spec.name, "fingerprint": campaign.fingerprint, "runs": len(runs)}
    return pa.schema(fields, metadata={_METADATA_KEY: json.dumps(metadata).encode()})


class ResultsTable:
    """The results of one campaign in ``directory`` (see the module docstring).

    Opening reads what is there and writes nothing; the directory is created by the first :meth:`append`.
    """

    def __init__(self, directory: Path, schema: pa.Schema, rows: dict[int, dict[str, Any]]):
        self.directory = Path(directory)
        self.schema = schema
        self._rows = rows
        self._fingerprint = self._metadata(schema)["fingerprint"]

    @classmethod
    def open(cls, directory: str | Path, campaign: Campaign, runs: Sequence[Run]) -> ResultsTable:
        """The table of ``campaign`` in ``directory``, with the rows already there (none for a new directory).

        Raises
        ------
        SpecError
            If the directory holds the results of another campaign (or of another version of this one).
        """
        table = cls(Path(directory), table_schema(campaign, runs), {})
        for path in table._stored_files():
            stored = pq.read_table(path)
            fingerprint = cls._metadata(stored.schema).get("fingerprint")
            if fingerprint != table._fingerprint:
                raise SpecError(f"{campaign.source}: results: {path} was written by another campaign or another "
                                f"version of this one or of its problem file (fingerprint {str(fingerprint)[:12]}, "
                                f"this campaign {table._fingerprint[:12]}); give another --out or remove it")
            for row in stored.to_pylist():
                table._rows.setdefault(row["run_id"], row)
        return table

    @staticmethod
    def _metadata(schema: pa.Schema) -> dict[str, Any]:
        raw = (schema.metadata or {}).get(_METADATA_KEY)
        return json.loads(raw) if raw else {}

    @property
    def path(self) -> Path:
        """The merged table file."""
        return self.directory / TABLE_FILE

    @property
    def finished(self) -> set[int]:
        """Run ids that have a row."""
        return set(self._rows)

    def rows(self) -> list[dict[str, Any]]:
        """Every row, by run id."""
        return [self._rows[i] for i in sorted(self._rows)]

    def append(self, run: Run, outcome: dict[str, Any]) -> dict[str, Any]:
        """Write the row of ``run`` with its ``outcome`` (status, message, objective, verified, wall time,
        figures, as :func:`convexguid.campaign.execute.run_task` returns them) as a part file; return the row."""
        row: dict[str, Any] = {"run_id": run.run_id, "sample": run.sample}
        for key, value in run.values.items():
            row[key] = float(value) if self.schema.field(key).type == pa.float64() else yaml_text(value)
        row.update(seed=run.seed, status=outcome["status"], message=outcome["message"],
                   objective=outcome["objective"], verified=outcome["verified"],
                   wall_time_s=outcome["wall_time_s"])
        row.update(outcome["figures"])
        row["overrides"] = list(run.overrides)
        parts = self.directory / PARTS_DIR
        parts.mkdir(parents=True, exist_ok=True)
        _write_atomic(pa.Table.from_pylist([row], schema=self.schema), parts / f"run-{run.run_id:08d}.parquet")
        self._rows[run.run_id] = row
        return row

    def compact(self) -> None:
        """Merge the part files into the table file and remove them (nothing to do without parts)."""
        parts_dir = self.directory / PARTS_DIR
        parts = sorted(parts_dir.glob("run-*.parquet"))
        if not parts:
            return
        _write_atomic(pa.Table.from_pylist(self.rows(), schema=self.schema), self.path)
        for part in parts + sorted(parts_dir.glob("*.tmp")):  # a .tmp is a part whose write was cut short
            part.unlink()
        parts_dir.rmdir()

    def _stored_files(self) -> list[Path]:
        """The table file (if any), then the part files."""
        main = [self.path] if self.path.is_file() else []
        return main + sorted((self.directory / PARTS_DIR).glob("run-*.parquet"))


def _write_atomic(table: pa.Table, path: Path) -> None:
    """Write ``table`` to ``path`` through :func:`~convexguid.outputs.atomic_file` (a part is whole or absent)."""
    with atomic_file(path, "wb") as fh:
        pq.write_table(table, fh)


def quantities(campaign: Campaign) -> list[str]:
    """The reported quantities: the objective, then the campaign's figures."""
    return ["objective", *campaign.spec.figures]


def grid_points(campaign: Campaign, rows: Sequence[dict[str, Any]]) -> list[tuple[tuple, list[dict[str, Any]]]]:
    """The rows grouped by grid point (the grid keys' values), in run order."""
    keys = [k for axis in campaign.spec.grid for k in axis.names]
    groups: dict[tuple, list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault(tuple(row[k] for k in keys), []).append(row)
    return list(groups.items())
