"""The example plugin examples/plugin_hello (sigcore-hello): built, installed, found, and working."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from sigcore import plugins
from sigcore.backend import Backend
from sigcore.sim import Simulation
from sigcore.world import WorldError, parse_world

EXAMPLE = Path(__file__).parent.parent / "examples" / "plugin_hello"

WORLD = """\
<world name="hello" timestep="0.01">
  <plugin name="hello" {attributes}/>
  <agent name="alice" controller="hello.greeter"/>
  <agent name="bob" controller="hello.greeter"/>
</world>
"""

PROBE = """\
import json, sys
import sigcore_hello
from sigcore import plugins
from sigcore.agent.controller import resolve_controller

print(json.dumps({
    "infos": [{"name": i.name, "distribution": i.distribution, "version": i.version, "error": i.error,
               "provides": i.provided()} for i in plugins.plugin_infos()],
    "feature": plugins.get_feature("hello").__qualname__,
    "controller": resolve_controller("hello.greeter", plugins.controllers()).__qualname__,
    "imported_from": sigcore_hello.__file__,
}))
"""


def _pip(*args: str, timeout: float) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "pip", "--disable-pip-version-check", "-q", *args],
                          capture_output=True, text=True, timeout=timeout)


@pytest.mark.slow
def test_built_and_installed_wheel_is_found_by_entry_point(tmp_path: Path) -> None:
    """A wheel of sigcore-hello, pip-installed in a new directory, is found with its controller, feature."""
    src = shutil.copytree(EXAMPLE, tmp_path / "src", ignore=shutil.ignore_patterns("build", "*.egg-info"))
    build = _pip("wheel", "--no-deps", "--no-build-isolation", "--no-index", "-w", str(tmp_path / "dist"),
                 str(src), timeout=60)
    if "invalid command 'bdist_wheel'" in build.stderr:
        pytest.skip("this venv's setuptools cannot build wheels (< 70.1, no 'wheel'): run scripts/setup.sh")
    assert build.returncode == 0, build.stderr
    [wheel] = (tmp_path / "dist").glob("sigcore_hello-0.1.0-*.whl")
    site = tmp_path / "site"
    install = _pip("install", "--no-deps", "--no-index", "--target", str(site), str(wheel), timeout=30)
    assert install.returncode == 0, install.stderr
    assert (site / "sigcore_hello-0.1.0.dist-info" / "entry_points.txt").read_text().split() == [
        "[sigcore]", "hello", "=", "sigcore_hello"]

    env = {**os.environ, "PYTHONPATH": str(site)}
    env.pop(plugins.DISABLE_ENV, None)
    probe = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env,
                           cwd=tmp_path, timeout=30)
    assert probe.returncode == 0, probe.stderr
    found = json.loads(probe.stdout)
    [hello] = [i for i in found["infos"] if i["name"] == "hello"]
    assert hello == {"name": "hello", "distribution": "sigcore-hello", "version": "0.1.0", "error": None,
                     "provides": ["feature hello", "controller hello.greeter"]}
    assert (found["feature"], found["controller"]) == ("HelloFeature", "Greeter")
    assert Path(found["imported_from"]).is_relative_to(site)


# ------------------------------------------------------------------ behaviour, in-process
def _noop(self: Backend, *args: Any, **kwargs: Any) -> None:
    """Every method of the null backend: the worlds here hold bare agents only, with no body to simulate."""


NullBackend: type[Backend] = type("NullBackend", (Backend,), {
    "name": "null", "__module__": __name__, **{method: _noop for method in Backend.__abstractmethods__}})


@pytest.fixture
def hello(monkeypatch: pytest.MonkeyPatch) -> Iterator[Any]:
    """The example plugin imported from its source tree and registered as 'hello' (autoload off)."""
    monkeypatch.setenv(plugins.DISABLE_ENV, "1")
    monkeypatch.syspath_prepend(str(EXAMPLE))
    plugins.reset_for_tests()
    import sigcore_hello

    plugins.register_plugin(sigcore_hello, name="hello")
    yield sigcore_hello
    plugins.reset_for_tests()
    for name in [m for m in sys.modules if m == "sigcore_hello" or m.startswith("sigcore_hello.")]:
        del sys.modules[name]


def world_sim(tmp_path: Path, attributes: str) -> Simulation:
    path = tmp_path / "hello.xml"
    path.write_text(WORLD.format(attributes=attributes))
    return Simulation(parse_world(path), NullBackend())


def test_registered_names(hello: Any) -> None:
    """The plugin provides the controller 'hello.greeter' and the feature 'hello', nothing else."""
    [info] = plugins.plugin_infos()
    assert info.provides == {"feature": ("hello",), "controller": ("hello.greeter",)}
    assert plugins.controllers()["hello.greeter"] is hello.Greeter
    assert plugins.get_feature("hello") is hello.HelloFeature


def test_feature_and_greeters_run(hello: Any, tmp_path: Path) -> None:
    """Greeters greet each other at start and count messages; the feature counts steps, greets each period."""
    sim = world_sim(tmp_path, 'greeting="hi" period="0.1"')
    sim.step(50)  # 0.5 s
    assert sim.features.summary() == {"hello": {"greeting": "hi", "steps": 50, "greetings": 5}}
    alice = sim.entities.controllers.controller("alice")
    assert isinstance(alice, hello.Greeter)
    # bob's greeting, then the feature's at 0.1 .. 0.4 s (the one at 0.5 s is delivered before step 51)
    assert (alice.received, alice.last) == (5, "hi")
    assert alice.actions == 2  # on_action at 0 s and 0.5 s
    assert sim.entities.controllers.failures == []


@pytest.mark.parametrize(("attributes", "column", "message"), [
    ("", 3, "required attribute 'greeting' is missing"),
    ('greeting=" "', 24, "the greeting is blank"),
    ('greeting="hi" period="-1"', 38, "'-1' is out of range; valid: period > 0 [s]"),
    ('greeting="hi" period="soon"', 38, "'soon' is not a number; valid: a number, period > 0 [s]"),
    ('greeting="hi" perod="1"', 38, "(did you mean 'period'?); valid: name, greeting, period"),
])
def test_feature_config_errors_name_the_attribute(hello: Any, tmp_path: Path, attributes: str, column: int,
                                                   message: str) -> None:
    """A bad <plugin name="hello"> attribute is a world error at that attribute's line and column."""
    with pytest.raises(WorldError) as e:
        world_sim(tmp_path, attributes)
    [issue] = e.value.issues
    assert (issue.line, issue.column) == (2, column) and message in issue.message


def test_greeter_alone_in_python(hello: Any, tmp_path: Path) -> None:
    """The greeter works without the feature too: each greeter receives exactly the other's greeting."""
    path = tmp_path / "plain.xml"
    path.write_text(textwrap.dedent("""\
        <world name="plain" timestep="0.01">
          <agent name="alice" controller="hello.greeter"/>
          <agent name="bob" controller="hello.greeter"/>
        </world>
        """))
    sim = Simulation(parse_world(path), NullBackend())
    sim.step(10)
    for me, other in (("alice", "bob"), ("bob", "alice")):
        greeter = sim.entities.controllers.controller(me)
        assert isinstance(greeter, hello.Greeter)
        assert (greeter.received, greeter.last) == (1, f"hello from {other}")
