"""``python -m heelstrike.cli``: the ``heelstrike`` command (as ``python -m heelstrike``)."""

from heelstrike.cli import main

if __name__ == "__main__":  # pragma: no cover - exercised through a subprocess in the tests
    raise SystemExit(main())
