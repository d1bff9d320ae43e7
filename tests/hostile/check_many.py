"""Run ``sigcore check`` or ``sigcore run`` on many world files in one process, after the imports.

Usage: ``python check_many.py COMMAND ARGS... -- WORLD...``: for each world, runs ``sigcore COMMAND WORLD ARGS...``
through typer's CliRunner and prints one JSON line (world, exit code, output, whether an exception escaped,
seconds); the last line is ``{"maxrss_kib": ...}``, this process's peak resident memory.
"""

from __future__ import annotations

import json
import resource
import sys
import time
import traceback


def main(argv: list[str]) -> None:
    """Check every world named in ``argv`` (see the module docstring)."""
    split = argv.index("--")
    command, worlds = argv[:split], argv[split + 1:]
    from typer.testing import CliRunner

    from sigcore import plugins
    from sigcore.cli import app

    plugins.load_plugins()
    runner = CliRunner()
    for world in worlds:
        start = time.perf_counter()
        result = runner.invoke(app, [command[0], world, *command[1:]])
        escaped = result.exception is not None and not isinstance(result.exception, SystemExit)
        output = result.output
        if escaped and result.exc_info is not None:
            output += "".join(traceback.format_exception(*result.exc_info))
        print(json.dumps({"world": world, "code": result.exit_code, "output": output[-4000:], "escaped": escaped,
                          "seconds": time.perf_counter() - start}), flush=True)
    print(json.dumps({"maxrss_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
