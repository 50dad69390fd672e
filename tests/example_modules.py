"""Loading an example module (a problem stated in Python under examples/) in a test, by its path there."""

import importlib.util
from pathlib import Path
from types import ModuleType

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load_example(relative: str) -> ModuleType:
    """The module ``examples/<relative>.py``, loaded afresh."""
    path = EXAMPLES / f"{relative}.py"
    spec = importlib.util.spec_from_file_location(f"example_{relative.replace('/', '_')}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
