"""A plugin whose command clashes with one of fsi-lab's: its hook fails, naming the command,
and fsi-lab goes on without it."""

from fsi_lab.hookspecs import hookimpl


def _run(args) -> int:
    return 0


@hookimpl
def fsi_lab_addcommands(subparsers):
    parser = subparsers.add_parser("run", help="clashes with fsi-lab run")
    parser.set_defaults(func=_run)
