"""The house's rules, checked on the source: PyBullet in one module, imports one way, one loop."""
import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "layered_swim"


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in PACKAGE.rglob("*.py")}


def imports(path: Path) -> set[str]:
    """Every layered_swim module ``path`` imports, at the top or inside a function. ``from pkg
    import name`` counts as importing ``pkg.name`` where that is a module."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("layered_swim")}
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("layered_swim"):
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                found.add(sub if sub in MODULES else node.module)
    return found


GRAPH = {name: imports(path) & set(MODULES) for name, path in MODULES.items()}


def test_pybullet_is_imported_only_by_the_world():
    users = {name for name, path in MODULES.items()
             if any(isinstance(n, (ast.Import, ast.ImportFrom)) and any(
                 (getattr(n, "module", None) or a.name).startswith("pybullet") for a in n.names)
                 for n in ast.walk(ast.parse(path.read_text())))}
    assert users == {"layered_swim.sim.world"}


def test_control_never_imports_the_simulation():
    offenders = {(m, d) for m, deps in GRAPH.items() if m.startswith("layered_swim.control")
                 for d in deps if d.startswith("layered_swim.sim")}
    assert not offenders


def test_rooms_import_only_downward():
    """Arrows run one way: cli/app -> commands -> analysis, render -> episode -> tasks, control, sim -> fluid,
    body -> state, geometry, outputs, config. (Listed: what each room may import besides itself.)"""
    base = {"config", "geometry", "state", "outputs"}
    allowed = {
        "config": set(), "geometry": set(), "state": {"geometry"},
        "body": base, "fluid": base | {"body"}, "sim": base | {"body", "fluid"},
        "control": base | {"body"}, "tasks": base | {"body", "control"},
        "episode": base | {"body", "fluid", "sim", "control", "tasks"}, "recorder": base | {"tasks"},
            "outputs": {"config"},
    }

    def room(module: str) -> str:
        return module.split(".")[1] if "." in module else module

    offenders = {(m, d) for m, deps in GRAPH.items() if room(m) in allowed
                 for d in deps if room(d) != room(m) and room(d) not in allowed[room(m)]}
    assert not offenders


def test_only_the_cli_imports_the_commands():
    """layered_swim/commands/ (one module per command) sits right under cli.py: nothing else imports
    it, and it never imports cli.py back (app.py reaches the app command through cli.main)."""
    def room(module: str) -> str:
        return module.split(".")[1] if "." in module else module

    offenders = {(m, d) for m, deps in GRAPH.items() for d in deps
                 if room(d) == "commands" and room(m) not in ("commands", "cli")}
    offenders |= {(m, d) for m, deps in GRAPH.items() if room(m) == "commands" for d in deps if room(d) == "cli"}
    assert not offenders


def test_no_import_cycles():
    state: dict[str, int] = {}      # 1 on the current path, 2 done

    def visit(module: str, path: list[str]) -> None:
        state[module] = 1
        for dep in sorted(GRAPH[module]):
            if state.get(dep) == 1:
                raise AssertionError("import cycle: " + " -> ".join(path[path.index(dep):] + [module, dep]))
            if dep not in state:
                visit(dep, path + [module])
        state[module] = 2

    for module in sorted(GRAPH):
        if module not in state:
            visit(module, [])


def test_the_episode_runner_is_the_only_loop():
    users = {name for name, path in MODULES.items() if "every_step" in path.read_text()}
    assert users == {"layered_swim.episode"}
