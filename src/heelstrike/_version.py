"""The package version: the one place it is written (``pyproject.toml`` reads it from here).

Kept in a module of its own so that ``import heelstrike`` and the generated-code cache keys do
not load :mod:`importlib.metadata` (about 25 ms a process).
"""

__version__ = "0.1.0"
