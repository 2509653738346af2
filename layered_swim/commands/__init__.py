"""The commands of ``layered-swim``, one module each (``layered_swim/cli.py`` puts them together).

Each module has ``add_parser(subparsers)``, which registers its sub-parser with its options and
help, and ``run(args)``, the command itself. Shared option builders live in ``options``, table
and number formatting in ``tables``.

Keep the modules' top-level imports light (argparse, json, math, pathlib, sys and the two modules
above): ``cli`` imports every command to build its parser, before ``main`` has moved C-level
stdout out of the way, and ``--help`` must stay fast. PyBullet, torch and the rest of the
package are imported inside ``run``.
"""

PROG = "layered-swim"
