"""``python -m satsim campaign SCENE --controller MODULE:FACTORY --period P [...]``: a
campaign stepped by your flight software, for clusters (contract section 15); see
``python -m satsim campaign --help``."""

import sys

from ._stepped import main


def _main() -> int:
    if len(sys.argv) < 2 or sys.argv[1] != "campaign":
        print("usage: python -m satsim campaign SCENE --controller MODULE:FACTORY --period P "
              "[--metrics MODULE:FUNC] [--workers N] [--shard I/N] [--resume] [--out DIR]",
              file=sys.stderr)
        return 2
    return main(sys.argv[2:])


if __name__ == "__main__":
    sys.exit(_main())
