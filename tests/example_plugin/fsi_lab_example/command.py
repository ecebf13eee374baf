"""A third-party ``fsi-lab`` subcommand: ``fsi-lab example-count FILE`` counts a file's lines."""

from pathlib import Path

from fsi_lab.contract import CliCommand
from fsi_lab.hookspecs import hookimpl


def _configure(parser):
    parser.add_argument("file", type=Path)


def _run(args) -> int:
    print(len(args.file.read_text().splitlines()))
    return 0


COMMAND = CliCommand(name="example-count", help="count the lines of a file",
                     configure=_configure, run=_run)


@hookimpl
def fsi_lab_addcommands(subparsers):
    COMMAND.add_to(subparsers)
