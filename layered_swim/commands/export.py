"""``layered-swim export``: a run folder's swim as BVH, glTF binary or USD ascii (Blender and
other tools; docs/export.md); and ``--export FILE`` of ``run`` and ``follow``, which export the
folder they have just written."""
from __future__ import annotations

from layered_swim.commands.options import count

DEFAULT_FPS = 30      # the log is 60 Hz; 30 is a video's rate and halves the files
FORMATS_HELP = "swim.bvh, swim.glb or swim.usda: the suffix picks the format (BVH, glTF binary, USD ascii)"


def add_parser(subparsers) -> None:
    command = subparsers.add_parser("export", help="write a run folder's swim as BVH, glTF or USD (for Blender ...)")
    command.add_argument("run", metavar="RUN_FOLDER", help="a `run` or `follow` folder (a stopped run's too: what it "
                                                          "logged)")
    command.add_argument("--to", required=True, metavar="FILE", help=FORMATS_HELP)
    command.add_argument("--fps", type=count(1, 240), default=DEFAULT_FPS,
                         help=f"frames per second, resampled from the 60 Hz log (default {DEFAULT_FPS})")
    command.add_argument("--overwrite", action="store_true", help="replace FILE if it exists")


def run(args) -> None:
    from layered_swim.export import check_target, export_run

    motion = export_run(args.run, check_target(args.to, args.overwrite), args.fps)
    partial = " (a stopped run: what it logged)" if motion.partial else ""
    print(f"wrote {motion.frames} frames at {motion.fps} fps of {len(motion.skeleton.names)} segments{partial} "
          f"to {args.to}")


def export_option(command) -> None:
    """``--export FILE`` for a command that writes one run folder."""
    command.add_argument("--export", metavar="FILE", help=f"also write the swim to FILE ({FORMATS_HELP}; "
                                                          f"{DEFAULT_FPS} fps; see `export`); an existing FILE is "
                                                          "replaced only with --overwrite")


def export_target(args):
    """The checked --export file (None without one): checked before the swim, not after it."""
    from layered_swim.export import check_target

    return None if args.export is None else check_target(args.export, args.overwrite)


def export_swim(target, run_dir) -> dict:
    """Export the folder just written to ``target``; what to add to the command's summary."""
    from layered_swim.export import export_run

    if target is None:
        return {}
    export_run(run_dir, target, DEFAULT_FPS)
    return {"exported_to": str(target.path)}
