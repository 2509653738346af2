"""The docs cannot drift from the code.

Every ``layered-swim ...``, ``python -m layered_swim ...`` and ``python app.py ...`` command line
in a fenced code block of README.md or docs/*.md is parsed by the real argument parser (parsing
only, nothing runs), and the names and files it gives are checked: strokes, trajectories,
experiments, policy files, run folders some other documented command writes. Every YAML example
is loaded as the file it shows. A few quick documented commands are run for real, shortened, into
tmp_path folders, and what they write is compared with docs/file-formats.md. Relative links
between the pages must resolve.
"""
from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import yaml

from layered_swim.cli import _parser

REPO = Path(__file__).resolve().parents[1]
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
FORMATS = REPO / "docs" / "file-formats.md"
SHELL_SEPARATORS = {"&&", "||", ";", "|", "&"}


@dataclass(frozen=True)
class Command:
    page: Path
    line: int
    program: str          # "layered-swim" or "app.py"
    args: tuple[str, ...]

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(REPO)}:{self.line}"

    def __str__(self) -> str:
        return " ".join([self.program, *self.args])


def fenced_blocks(page: Path) -> list[tuple[str, list[tuple[int, str]]]]:
    """(language, [(line number, text)]) of every fenced code block."""
    blocks, current, language = [], None, ""
    for number, text in enumerate(page.read_text().splitlines(), start=1):
        if text.lstrip().startswith("```"):
            if current is None:
                current, language = [], text.strip()[3:].strip().lower()
            else:
                blocks.append((language, current))
                current = None
        elif current is not None:
            current.append((number, text))
    assert current is None, f"{page}: a code block is not closed"
    return blocks


def shell_lines(block: list[tuple[int, str]]) -> list[tuple[int, str]]:
    """Lines with backslash continuations joined, numbered by their first line."""
    lines, pending, start = [], "", 0
    for number, text in block:
        if not pending:
            start = number
        if text.rstrip().endswith("\\"):
            pending += text.rstrip()[:-1] + " "
            continue
        lines.append((start, pending + text))
        pending = ""
    return lines


def segments(text: str) -> list[list[str]]:
    """The simple commands of a shell line (split at &&, ;, | ...), comments left out."""
    lexer = shlex.shlex(text, posix=True, punctuation_chars=True)
    lexer.whitespace_split = True
    lexer.commenters = "#"
    parts, current = [], []
    for token in lexer:
        if token in SHELL_SEPARATORS:
            parts.append(current)
            current = []
        else:
            current.append(token)
    return [p for p in parts + [current] if p]


def as_command(tokens: list[str]) -> tuple[str, list[str]] | None:
    """("layered-swim" | "app.py", arguments) for one of ours, else None."""
    while tokens and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*=.*", tokens[0]):     # VAR=value prefixes
        tokens = tokens[1:]
    if tokens[:1] == ["xvfb-run"]:
        tokens = tokens[1:]
    if not tokens:
        return None
    program = Path(tokens[0]).name
    if program == "layered-swim":
        return "layered-swim", tokens[1:]
    if re.fullmatch(r"python3?", program):
        if tokens[1:3] == ["-m", "layered_swim"]:
            return "layered-swim", tokens[3:]
        if tokens[1:2] == ["app.py"]:
            return "app.py", tokens[2:]
    return None


def documented_commands() -> list[Command]:
    found = []
    for page in PAGES:
        for language, block in fenced_blocks(page):
            if language not in ("", "sh", "bash", "shell", "console"):
                continue
            for number, text in shell_lines(block):
                try:
                    parts = segments(text)
                except ValueError as err:          # unbalanced quotes: not a shell line
                    if "layered-swim" in text or "app.py" in text:
                        raise AssertionError(f"{page.relative_to(REPO)}:{number}: cannot split '{text}': {err}")
                    continue
                for tokens in parts:
                    ours = as_command(tokens)
                    if ours:
                        found.append(Command(page, number, ours[0], tuple(ours[1])))
    return found


def yaml_examples() -> list[tuple[str, dict]]:
    examples = []
    for page in PAGES:
        for language, block in fenced_blocks(page):
            if language in ("yaml", "yml"):
                where = f"{page.relative_to(REPO)}:{block[0][0] if block else 0}"
                examples.append((where, yaml.safe_load("\n".join(text for _, text in block))))
    return examples


COMMANDS = documented_commands()
EXAMPLES = yaml_examples()


CLI_PARSER = _parser()


def _app_parser():
    """``python app.py``'s parser: the CLI's ``app`` command where there is one, else app.py's own."""
    for action in CLI_PARSER._actions:
        if isinstance(action, argparse._SubParsersAction) and "app" in action.choices:
            return action.choices["app"]
    spec = importlib.util.spec_from_file_location("_docs_app", REPO / "app.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.parser()


APP_PARSER = _app_parser()


def parse(command: Command):
    """The namespace the real parser makes of the line; None for --help (which exits 0)."""
    parser = CLI_PARSER if command.program == "layered-swim" else APP_PARSER
    stderr = io.StringIO()
    try:
        with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
            return parser.parse_args(list(command.args))
    except SystemExit as exit_:
        if exit_.code == 0:
            return None
        raise AssertionError(f"{command.where}: `{command}` does not parse: {stderr.getvalue().strip()}") from None


def _outputs() -> set[Path]:
    """Every --out a documented command gives: folders other documented commands may read."""
    outs = set()
    for command in COMMANDS:
        try:
            args = parse(command)
        except AssertionError:         # reported, with its file and line, by test_documented_command_parses
            continue
        if args is not None and getattr(args, "out", None):
            outs.add(Path(args.out))
    return outs


OUTPUTS = _outputs()
EXAMPLE_NAMES = {data.get("name") for _, data in EXAMPLES if isinstance(data, dict)}


def check_names(command: Command, args) -> None:
    """What the line names exists: strokes, trajectories, experiments, files and folders."""
    from layered_swim.analysis.experiments import EXPERIMENTS
    from layered_swim.control.stroke import available_strokes
    from layered_swim.control.targets import available_trajectories

    where = f"{command.where}: `{command}`"
    strokes, trajectories = set(available_strokes()), set(available_trajectories())

    def stroke(name: str) -> None:
        if name.endswith((".yaml", ".yml")):
            assert (REPO / name).is_file(), f"{where}: no stroke file {name}"
        else:
            assert name in strokes | {"auto"}, f"{where}: unknown stroke {name!r}"

    def trajectory(name: str) -> None:
        if name.endswith((".yaml", ".yml")):
            assert (REPO / name).is_file() or Path(name).stem in EXAMPLE_NAMES, \
                f"{where}: {name} is neither a file nor a trajectory example in the docs"
        else:
            assert name in trajectories, f"{where}: unknown trajectory {name!r}"

    def produced(path: str, what: str) -> None:
        assert (REPO / path).exists() or Path(path) in OUTPUTS or Path(path).parent in OUTPUTS, \
            f"{where}: {what} {path} is not in the repository, and no documented command writes it"

    if getattr(args, "stroke", None):
        stroke(args.stroke)
    for name in (getattr(args, "strokes", None) or "").split(","):
        if name:
            stroke(name)
    if getattr(args, "command", None) == "follow" or getattr(args, "trajectory", None):
        trajectory(args.trajectory)
    if getattr(args, "command", None) == "render":
        if args.source not in trajectories:
            produced(args.source, "run folder")
    if getattr(args, "command", None) == "experiment":
        assert args.name in set(EXPERIMENTS) | {"list"}, f"{where}: unknown experiment {args.name!r}"
    if getattr(args, "run", None):
        produced(args.run, "run folder")
    if getattr(args, "policy", None):
        produced(args.policy, "policy")
    if getattr(args, "config", None) and args.command == "run":      # a run folder's config.json
        produced(str(Path(args.config).parent), "run folder")
    elif getattr(args, "config", None):
        assert (REPO / args.config).is_file(), f"{where}: no file {args.config}"
    if getattr(args, "current", None):
        values = args.current.split(",")
        assert len(values) == 3 and all(abs(float(v)) <= 5 for v in values), f"{where}: --current {args.current}"
    if getattr(args, "size", None):
        assert re.fullmatch(r"\d+x\d+", args.size), f"{where}: --size {args.size}"


def test_the_docs_show_commands():
    pages = {c.page.name for c in COMMANDS}
    assert {"README.md", "cli.md"} <= pages
    assert {c.args[0] for c in COMMANDS if c.program == "layered-swim" and c.args} >= {
        "run", "strokes", "validate", "calibrate", "follow", "goal", "render", "analyze", "compare", "experiment",
        "train", "soak", "bench", "fit-stroke"}, "docs/cli.md should show every command"
    assert any(c.program == "app.py" for c in COMMANDS)


@pytest.mark.parametrize("command", COMMANDS, ids=[f"{c.where} {c}"[:90] for c in COMMANDS])
def test_documented_command_parses(command):
    args = parse(command)
    if args is not None:
        check_names(command, args)


@pytest.mark.parametrize("where, data", EXAMPLES, ids=[w for w, _ in EXAMPLES])
def test_yaml_example_loads(where, data):
    from layered_swim.body.layout import joint_layout
    from layered_swim.body.model import load_body
    from layered_swim.config import ConfigError
    from layered_swim.config import parse as parse_model
    from layered_swim.control.stroke import StrokeSpec, build_stroke
    from layered_swim.control.targets import build_trajectory, parse_trajectory

    try:
        if isinstance(data, dict) and "type" in data:
            build_trajectory(parse_trajectory(data, where), where)
        elif isinstance(data, dict) and "knobs" in data:
            from layered_swim.analysis.stroke_fit import load_fit

            with tempfile.TemporaryDirectory() as tmp:
                (Path(tmp) / "fit.yaml").write_text(yaml.safe_dump(data))
                load_fit(Path(tmp) / "fit.yaml")
        elif isinstance(data, dict) and "period_s" in data:
            build_stroke(parse_model(StrokeSpec, data, where), joint_layout(load_body()), where)
        elif isinstance(data, dict) and "env" in data:
            from layered_swim.rl.config import load_train_spec

            with tempfile.TemporaryDirectory() as tmp:
                (Path(tmp) / "train.yaml").write_text(yaml.safe_dump(data))
                load_train_spec(Path(tmp) / "train.yaml")
        elif isinstance(data, dict) and "flows" in data:
            from layered_swim.fluid.flow_field import FlowField, parse_water

            FlowField(parse_water(data, where), where)
        else:
            raise AssertionError(f"{where}: a YAML example of no known kind (trajectory, stroke, fit, water "
                                 "or training)")
    except ConfigError as err:
        raise AssertionError(f"{where}: {err}") from None


def _slug(heading: str) -> str:
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower().replace("`", ""))
    return text.replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    inside, anchors = False, set()
    for text in page.read_text().splitlines():
        if text.lstrip().startswith("```"):
            inside = not inside
        elif not inside and text.startswith("#"):
            anchors.add(_slug(text.lstrip("#")))
    return anchors


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_links_resolve(page):
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+:", target):
            continue
        path, _, anchor = target.partition("#")
        linked = (page.parent / path).resolve() if path else page
        assert linked.exists(), f"{page.name}: link to {target}: no such file"
        if anchor and linked.suffix == ".md":
            assert anchor in _anchors(linked), f"{page.name}: link to {target}: no such heading"


# ---------------------------------------------------------------- a few commands, run

def documented(pattern: str) -> Command:
    """The first documented command matching ``pattern``: what runs is what the docs show."""
    for command in COMMANDS:
        if command.program == "layered-swim" and re.fullmatch(pattern, str(command)):
            return command
    raise AssertionError(f"no documented command matches {pattern!r}; update this test with the docs")


def changed(command: Command, **options) -> list[str]:
    """The command's arguments with ``--option value`` replaced (or added)."""
    args = list(command.args)
    for name, value in options.items():
        flag = "--" + name.replace("_", "-")
        if flag in args:
            args[args.index(flag) + 1] = str(value)
        else:
            args += [flag, str(value)]
    return args


def cli(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    env.pop("DISPLAY", None)
    result = subprocess.run([sys.executable, "-m", "layered_swim", *args], cwd=cwd, env=env,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, f"layered-swim {' '.join(args)}: {result.stderr}"
    return result


def section(page: Path, heading: str) -> str:
    text = page.read_text()
    start = text.index(heading)
    following = re.search(r"^#{1,3} ", text[start + len(heading):], flags=re.M)
    return text[start:start + len(heading) + following.start()] if following else text[start:]


def first_cells(text: str) -> set[str]:
    """Backticked names in the first column of the markdown tables in ``text``."""
    names = set()
    for row in text.splitlines():
        if row.startswith("|") and not row.startswith("|---"):
            names |= set(re.findall(r"`([\w.-]+)`", row.split("|")[1]))
    return names


def backticked(text: str) -> set[str]:
    return set(re.findall(r"`([\w.]+)`", text))


def test_strokes_lists_what_the_readme_shows(tmp_path):
    shown = cli(list(documented(r"layered-swim strokes").args), tmp_path).stdout
    listed = {line.split()[0]: line.split()[1:3] for line in shown.splitlines()[1:] if line.strip()
              and not line.startswith("auto:")}
    readme = section(REPO / "README.md", "| stroke | cycles/min |")
    table = {}
    for row in readme.splitlines()[2:]:
        if not row.startswith("|"):
            break
        cells = [c.strip() for c in row.strip("|").split("|")]
        names = re.findall(r"`(\w+)`", cells[0])
        table.update({n: [cpm, speed] for n, cpm, speed in zip(names, cells[1].split(", "), cells[2].split(", "))})
    assert table == listed


def test_validate_drag_as_documented(tmp_path):
    rows = json.loads(cli(list(documented(r"layered-swim validate drag").args) + ["--json"], tmp_path).stdout)
    assert [r["speed_m_s"] for r in rows] == [0.5, 1.0, 1.5, 2.0, 2.5]
    assert all(0.95 < r["ratio"] < 1.05 for r in rows)


def test_experiment_list_matches_the_experiments_page(tmp_path):
    listed = {line.split()[0] for line in cli(["experiment", "list"], tmp_path).stdout.splitlines()[1:] if line.strip()}
    documented(r"layered-swim experiment list")
    page = section(REPO / "docs" / "experiments.md", "## Results")
    assert first_cells(page) == listed


def test_run_writes_what_file_formats_describes(tmp_path):
    command = documented(r"layered-swim run --stroke front_crawl --seconds \d+ --out \S+")
    out = tmp_path / "run"
    cli(changed(command, seconds=1, out=out), tmp_path)
    assert {"summary.json", "config.json", "log.npz", "timeseries.csv"} <= {p.name for p in out.iterdir()}
    summary = json.loads((out / "summary.json").read_text())
    described = first_cells(section(FORMATS, "### summary.json"))
    conditional = {"partial", "fluid", "memory", "finite"}
    assert set(summary) == described - conditional
    config = json.loads((out / "config.json").read_text())
    assert set(config) <= backticked(section(FORMATS, "### config.json"))
    with np.load(out / "log.npz") as log:
        arrays = set(log.files) - {"segment_names", "joint_names", "pose_names"}
    assert arrays == first_cells(section(FORMATS, "### log.npz"))
    columns = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    assert set(columns) == backticked(section(FORMATS, "### timeseries.csv"))


def test_follow_the_readme_example_then_render_it(tmp_path):
    """The README's own trajectory, saved as it says, followed as it says (shortened), then drawn."""
    where, example = next((w, d) for w, d in EXAMPLES if w.startswith("README.md"))
    path = tmp_path / f"{example['name']}.yaml"
    path.write_text(yaml.safe_dump(example))
    command = documented(rf"layered-swim follow {re.escape(path.name)} .*")
    out = tmp_path / "follow"
    cli(changed(command, seconds=2, out=out), tmp_path)
    files = {p.name for p in out.iterdir()}
    assert {"summary.json", "config.json", "log.npz", "timeseries.csv", "track.npz"} <= files
    summary = json.loads((out / "summary.json").read_text())
    described = (backticked(section(FORMATS, "### summary.json"))
                 | backticked(section(REPO / "docs" / "cli.md", "## follow")))
    assert set(summary) <= described
    config = json.loads((out / "config.json").read_text())
    assert set(config) <= backticked(section(FORMATS, "### config.json"))
    with np.load(out / "track.npz") as track:
        assert set(track.files) == backticked(section(FORMATS, "### track.npz")) - {"follow"}

    render = documented(r"layered-swim render runs/\S+ --out \S+")
    args = changed(render, out=tmp_path / "frames", seconds=1, fps=2, size="320x180")
    args[args.index(render.args[1])] = str(out)
    assert "wrote" in cli(args, tmp_path).stdout
    assert len(list((tmp_path / "frames").glob("frame_*.png"))) >= 2
