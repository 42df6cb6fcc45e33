"""The ``mint`` command that the wheel installs: the whole command line,
run by the extension module (no Rust toolchain needed)."""

import sys

from . import _mint


def main() -> None:
    """Runs ``mint`` with ``sys.argv`` and exits with its status."""
    argv = ["mint"] + sys.argv[1:]
    sys.exit(_mint.cli_main(argv))


if __name__ == "__main__":
    main()
