"""``fsi-lab plugin new KIND NAME [--dir DIR]``: the start of a plugin distribution.

It writes ``DIR/fsi-lab-NAME/``: a ``pyproject.toml`` declaring the plugin's entry point in the
``fsi_lab`` group, the package ``fsi_lab_NAME`` (the module that declares the plugin, kept
light, and the module doing the work), a test file that runs fsi-lab's conformance kit
(:mod:`fsi_lab.testing`) on it, and a README saying how to install, test and use it. As
written, it installs with ``pip install -e 'DIR/fsi-lab-NAME[test]'`` and passes its tests;
the author then changes what it computes, sends or talks to.

This module is a built-in plugin (the ``scaffold`` entry point) adding the command through the
``fsi_lab_addcommands`` hook; it imports the templates only when the command runs.
"""

from __future__ import annotations

import argparse
import re
import shlex
import sys
from pathlib import Path

from fsi_lab.hookspecs import hookimpl

KINDS = ("analysis", "excitation", "instrument")
#: A plugin name: lower-case words of letters and digits joined by dashes, starting with a letter.
NAME_PATTERN = re.compile(r"^[a-z][a-z0-9]*(-[a-z0-9]+)*$")


def plugin_name(text: str) -> str:
    """``text`` as a plugin name (argparse type); ArgumentTypeError saying what is accepted."""
    if not NAME_PATTERN.match(text) or len(text) > 40:
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected lower-case words of letters and digits joined by dashes, "
            "starting with a letter, at most 40 characters (e.g. peak-ratio)")
    return text


def scaffold(kind: str, name: str, parent: Path) -> Path:
    """Write the distribution of a ``kind`` plugin called ``name`` into ``parent``.

    Returns
    -------
    Path
        The distribution's folder, ``parent / f"fsi-lab-{name}"``.

    Raises
    ------
    fsi_lab.errors.InputFileError
        The folder exists already, or ``parent`` is not a folder.
    """
    from fsi_lab.errors import InputFileError
    from fsi_lab.scaffold.templates import files

    if parent.exists() and not parent.is_dir():
        raise InputFileError(f"{parent}: is not a folder; --dir names the folder the plugin's "
                             "distribution is written in")
    root = parent / f"fsi-lab-{name}"
    if root.exists():
        raise InputFileError(f"{root}: exists already; choose another NAME or --dir (nothing "
                             "was written)")
    for relative, text in files(kind, name).items():
        path = root / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root


def run(args: argparse.Namespace) -> int:
    """``fsi-lab plugin new``."""
    root = scaffold(args.kind, args.name, args.dir)
    package = "fsi_lab_" + args.name.replace("-", "_")
    print(f"wrote {root}/ (pyproject.toml, {package}/, tests/, README.md)")
    # The Python that runs this fsi-lab: its plugins must be installed there (a bare pip may
    # be another environment's, which would fetch fsi-lab from the package index).
    python = shlex.quote(sys.executable)
    print("next:")
    print(f"  {python} -m pip install -e '{root}[test]'   # fsi-lab plugins then lists "
          f"{args.name}")
    print(f"  cd {root} && {python} -m pytest   # fsi-lab's conformance kit on it")
    print(f"  edit {package}/ (its README says what to change)")
    return 0


def configure(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``fsi-lab plugin``."""
    actions = parser.add_subparsers(dest="plugin_command", required=True, metavar="ACTION")
    new = actions.add_parser("new", help="write a plugin distribution ready to install and test",
                             description=__doc__.split("\n\n")[1])
    new.add_argument("kind", choices=KINDS, metavar="KIND",
                     help=f"the kind of plugin: {', '.join(KINDS)}")
    new.add_argument("name", type=plugin_name, metavar="NAME",
                     help="the plugin's name, e.g. peak-ratio")
    new.add_argument("--dir", type=Path, default=Path("."), metavar="DIR",
                     help="folder to write fsi-lab-NAME/ in (default: the current folder)")
    new.set_defaults(func=run)


@hookimpl
def fsi_lab_addcommands(subparsers) -> None:
    """``fsi-lab plugin new KIND NAME [--dir DIR]``."""
    configure(subparsers.add_parser("plugin", help="write a new plugin distribution "
                                                   "(fsi-lab plugin new KIND NAME)"))


if __name__ == "__main__":  # python -m fsi_lab.scaffold new KIND NAME
    main_parser = argparse.ArgumentParser(prog="fsi-lab plugin")
    configure(main_parser)
    parsed = main_parser.parse_args()
    sys.exit(parsed.func(parsed))
