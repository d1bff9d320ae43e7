"""Hostile user code and plugins (issue 17, defects 6-9): markup in their text, ``sys.exit``, failing features, slow
controllers. Real controllers and plugins are written to ``tmp_path`` (plugins as installed distributions: a
``*.dist-info`` with an entry point) and run through the real CLI in a subprocess where exit codes and output
matter."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import pytest

from sigcore import plugins
from sigcore.errors import BudgetError
from sigcore.isolation import CallbackBudget
from sigcore.sim import Simulation, run
from sigcore.world import parse_world

ROOT = Path(__file__).parent.parent

CONTROLLERS = '''
import sys
import time

from sigcore.agent import Controller


class Markup(Controller):
    def on_action(self, ctx):
        raise RuntimeError("cannot open [/tmp/data] [bold]x[/bold], waited 2 [s]")


class Exits(Controller):
    def on_action(self, ctx):
        sys.exit(3)


class Counting(Controller):
    """Counts its on_action calls in a file next to this module (every 0.1 s)."""

    calls = 0

    def on_action(self, ctx):
        Counting.calls += 1
        with open(__file__ + ".calls", "w") as f:
            f.write(str(Counting.calls))
        return 0.1


class Slow(Counting):
    """Takes 0.3 s of wall time in each on_action."""

    def on_action(self, ctx):
        time.sleep(0.3)
        return super().on_action(ctx)
'''

EXIT_AT_IMPORT = "import sys\nsys.exit(0)\n"

FLAKY = '''
import sys

import sigcore
from pydantic import Field
from sigcore.feature import Feature, FeatureConfig


class FlakyConfig(FeatureConfig):
    fail: str = Field(default="", description="what fails: init, init-exit, step, step-exit, message, reset, "
                      "summary, report, outcome")
    at: int = Field(default=50, gt=0, description="the step at which the step observer fails")


class Flaky(Feature):
    name = "flaky"
    config_model = FlakyConfig

    def __init__(self, sim, config):
        self.fail, self.at = config.fail, config.at
        self.steps = self.messages = self.resets = 0
        if self.fail == "init":
            raise RuntimeError("no [/dev/flaky] device")
        if self.fail == "init-exit":
            sys.exit(5)
        sim.events.subscribe("step", self._on_step)
        sim.events.subscribe("message", self._on_message)
        sim.features.register_service("flaky_service", self._on_service)

    def _on_step(self, sim):
        self.steps += 1
        if self.steps == self.at and self.fail == "step":
            raise RuntimeError("lost [/tmp/data] after 0.1 [s]")
        if self.steps == self.at and self.fail == "step-exit":
            sys.exit(6)

    def _on_message(self, msg):
        self.messages += 1
        if self.fail == "message":
            raise KeyError(msg.content)

    def _on_service(self, sender, text):
        pass

    def reset(self):
        self.resets += 1
        if self.fail == "reset":
            raise ValueError("cannot reset")

    def summary(self):
        if self.fail == "summary":
            raise RuntimeError("no summary")
        return {"steps": self.steps, "note": "[bold]kept[/bold]"}

    def report(self):
        if self.fail == "report":
            raise RuntimeError("no report")
        return ["  flaky table: [red]not red[/red] 1.5 [s]"]

    def outcome(self):
        if self.fail == "outcome":
            raise RuntimeError("no verdict")
        return None


@sigcore.hookimpl
def sigcore_register_features(register):
    register(Flaky)


@sigcore.hookimpl
def sigcore_simulation_started(simulation):
    sys.exit(7)
'''

FAULTY_TRANSPORT = '''
import sigcore
from sigcore.transport import Transport


class Faulty(Transport):
    """A transport whose step observer raises at step 100 (a bug in a transport, not user code)."""

    name = "faulty"

    def start(self, sim):
        sim.events.subscribe("step", self._on_step)

    def _on_step(self, sim):
        if sim.step_count == 100:
            raise RuntimeError("transport bug [/x]")

    def service(self, timeout):
        pass

    def stop(self):
        pass


@sigcore.hookimpl
def sigcore_register_transports(register):
    register(Faulty)
'''

BROKEN_PLUGIN = '''
raise RuntimeError("[red]broken[/red] plugin [/tmp/x]")
'''

WORLD = '''<world name="iso" timestep="0.002">
  <object name="ball" shape="sphere" size="0.05" mass="0.3" pose="0 0 0.05"/>
  <agent name="moderator"{controller}/>
{plugin}</world>
'''


def world(tmp_path: Path, controller: str = "", plugin: str = "") -> Path:
    """A small world file: a ball and an agent ``moderator`` with ``controller``, and a ``<plugin>`` line."""
    path = tmp_path / "iso.xml"
    attr = f' controller="{controller}"' if controller else ""
    path.write_text(WORLD.format(controller=attr, plugin=f"  {plugin}\n" if plugin else ""))
    return path


def site(tmp_path: Path) -> Path:
    """The directory put on PYTHONPATH: controller modules and fake installed plugin distributions."""
    path = tmp_path / "site"
    path.mkdir(exist_ok=True)
    return path


def install(tmp_path: Path, name: str, source: str) -> Path:
    """Write plugin module ``sigcore_iso_<name>`` as an installed distribution with entry point ``<name>``."""
    where = site(tmp_path)
    module = f"sigcore_iso_{name}"
    (where / f"{module}.py").write_text(textwrap.dedent(source))
    info = where / f"sigcore_iso_{name}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: sigcore-iso-{name}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[{plugins.GROUP}]\n{name} = {module}\n")
    return where


def controllers(tmp_path: Path) -> Path:
    """Write the controllers module ``iso_controllers`` and return its directory."""
    where = site(tmp_path)
    (where / "iso_controllers.py").write_text(CONTROLLERS)
    return where


def sigcore(tmp_path: Path, *args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """Run the real ``sigcore`` command with ``tmp_path/site`` on PYTHONPATH."""
    env = {**os.environ, "PYTHONPATH": str(site(tmp_path))}
    return subprocess.run([sys.executable, "-m", "sigcore", *args], capture_output=True, text=True, cwd=tmp_path,
                          timeout=timeout, env=env)


def batch(tmp_path: Path, path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """``sigcore run PATH --transport none --steps 300 --quiet`` plus ``args``."""
    return sigcore(tmp_path, "run", str(path), "--transport", "none", "--steps", "300", "--quiet", *args)


def calls(tmp_path: Path) -> int:
    """How many on_action calls a Counting controller made."""
    return int((site(tmp_path) / "iso_controllers.py.calls").read_text())


# ------------------------------------------------------------------ defect 6: markup
@pytest.mark.slow
def test_markup_in_a_controller_error_is_printed_as_is(tmp_path: Path) -> None:
    """A controller error with [/tmp/data], [bold] and [s] is printed verbatim; the report is complete, exit 0."""
    controllers(tmp_path)
    r = batch(tmp_path, world(tmp_path, "iso_controllers:Markup"))
    assert r.returncode == 0, r.stderr
    assert ("controller of 'moderator' disabled (on_action at t=0.000 s): RuntimeError: cannot open [/tmp/data] "
            "[bold]x[/bold], waited 2 [s]") in r.stdout
    assert "steps:    300" in r.stdout and "Traceback" not in r.stderr + r.stdout


@pytest.mark.slow
def test_markup_in_a_plugin_error_is_shown_as_is(tmp_path: Path) -> None:
    """`sigcore plugins` shows a failed plugin's error with its brackets verbatim, FAILED, exit 0."""
    install(tmp_path, "broken", BROKEN_PLUGIN)
    r = sigcore(tmp_path, "plugins")
    assert r.returncode == 0, r.stderr
    table = " ".join(r.stdout.replace("│", " ").split())  # cells wrap: compare the words
    assert "broken sigcore-iso-broken 0.1 FAILED: importing 'sigcore_iso_broken' raised RuntimeError:" in table
    assert "[red]broken[/red] plugin [/tmp/x]" in table and "Traceback" not in r.stderr


@pytest.mark.slow
def test_markup_in_feature_summary_and_report_is_printed_as_is(tmp_path: Path) -> None:
    """A feature's summary and report lines with [tags] and [s] are printed verbatim."""
    install(tmp_path, "flaky", FLAKY)
    r = batch(tmp_path, world(tmp_path, plugin='<plugin name="flaky"/>'))
    assert r.returncode == 0, r.stderr
    assert "flaky: {'steps': 300, 'note': '[bold]kept[/bold]'}" in r.stdout
    assert "  flaky table: [red]not red[/red] 1.5 [s]" in r.stdout.splitlines()


# ------------------------------------------------------------------ defect 7: sys.exit
@pytest.mark.slow
def test_sys_exit_in_on_action_disables_the_controller(tmp_path: Path) -> None:
    """sys.exit(3) in on_action disables that controller with its agent named; the run goes on to its end."""
    controllers(tmp_path)
    r = batch(tmp_path, world(tmp_path, "iso_controllers:Exits"))
    assert r.returncode == 0, r.stderr
    assert "controller of 'moderator' disabled (on_action at t=0.000 s): SystemExit: sys.exit(3) was called" \
        in r.stdout
    assert "steps:    300" in r.stdout and "Traceback" not in r.stderr


@pytest.mark.slow
def test_sys_exit_in_a_controller_module_fails_check(tmp_path: Path) -> None:
    """A controller module calling sys.exit(0) at import makes `sigcore check` exit 2 with a located message."""
    (site(tmp_path) / "iso_exits.py").write_text(EXIT_AT_IMPORT)
    path = world(tmp_path, "iso_exits:Thing")
    r = sigcore(tmp_path, "check", str(path), "--transport", "none")
    assert r.returncode == 2, r.stdout + r.stderr
    assert r.stderr.startswith(f"{path}:3:") and "agent 'moderator'" in r.stderr
    assert "importing 'iso_exits' for controller 'iso_exits:Thing' raised SystemExit: sys.exit(0)" in r.stderr
    assert "Traceback" not in r.stderr and "ok" not in r.stdout


@pytest.mark.slow
def test_sys_exit_in_a_plugin_at_import_is_a_failed_plugin(tmp_path: Path) -> None:
    """A plugin calling sys.exit(0) at import is FAILED in `sigcore plugins`; `check` of a world using it exits 2."""
    install(tmp_path, "quitter", EXIT_AT_IMPORT)
    r = sigcore(tmp_path, "plugins")
    assert r.returncode == 0 and "mujoco" in r.stdout, r.stderr
    table = " ".join(r.stdout.replace("│", " ").split())
    assert "quitter sigcore-iso-quitter 0.1 FAILED: importing 'sigcore_iso_quitter' raised SystemExit: " \
           "sys.exit(0) was called" in table
    path = world(tmp_path, plugin='<plugin name="quitter"/>')
    r = sigcore(tmp_path, "check", str(path), "--transport", "none")
    assert r.returncode == 2, r.stdout + r.stderr
    assert f"{path}:4:" in r.stderr and "feature 'quitter' is not registered" in r.stderr
    assert "'quitter' (sigcore-iso-quitter 0.1): importing 'sigcore_iso_quitter' raised SystemExit" in r.stderr
    assert "Traceback" not in r.stderr


@pytest.mark.slow
def test_sys_exit_in_a_plugin_hook_is_logged_and_the_run_goes_on(tmp_path: Path) -> None:
    """sys.exit in a plugin's sigcore_simulation_started hook is logged with the plugin's name; the run ends."""
    install(tmp_path, "flaky", FLAKY)
    r = batch(tmp_path, world(tmp_path, plugin='<plugin name="flaky"/>'))
    assert r.returncode == 0, r.stderr
    assert "plugin 'flaky' raised in sigcore_simulation_started: SystemExit: sys.exit(7) was called" in r.stderr
    assert "steps:    300" in r.stdout


# ------------------------------------------------------------------ defect 8: features that fail
@pytest.mark.slow
@pytest.mark.parametrize(("fail", "error"), [("init", "RuntimeError: no [/dev/flaky] device"),
                                             ("init-exit", "SystemExit: sys.exit(5) was called")])
def test_feature_failing_in_its_constructor_is_named_with_its_line(tmp_path: Path, fail: str, error: str) -> None:
    """A feature whose constructor raises (or exits) is named with its <plugin> line, exit 2; the backend is not
    blamed."""
    install(tmp_path, "flaky", FLAKY)
    path = world(tmp_path, plugin=f'<plugin name="flaky" fail="{fail}"/>')
    r = sigcore(tmp_path, "check", str(path), "--transport", "none")
    assert r.returncode == 2, r.stdout + r.stderr
    assert r.stderr.strip() == f"{path}:4: feature 'flaky' failed while being created: {error}"


@pytest.mark.slow
@pytest.mark.parametrize(("fail", "line"), [
    ("step", "feature 'flaky' disabled (step observer at t=0.100 s): RuntimeError: lost [/tmp/data] after 0.1 [s]"),
    ("step-exit", "feature 'flaky' disabled (step observer at t=0.100 s): SystemExit: sys.exit(6) was called"),
    ("summary", "feature 'flaky' disabled (summary at t=0.600 s): RuntimeError: no summary"),
    ("report", "feature 'flaky' disabled (report at t=0.600 s): RuntimeError: no report"),
])
def test_feature_failing_while_running_is_disabled_and_reported(tmp_path: Path, fail: str, line: str) -> None:
    """A feature that raises (or exits) while running or reporting is disabled, the run goes to its end, the report
    has one line for it, and no traceback is printed."""
    install(tmp_path, "flaky", FLAKY)
    r = batch(tmp_path, world(tmp_path, plugin=f'<plugin name="flaky" fail="{fail}"/>'))
    assert r.returncode == 0, r.stderr
    assert f"  {line}" in r.stdout.splitlines()
    assert "steps:    300" in r.stdout and "Traceback" not in r.stderr + r.stdout


@pytest.mark.slow
def test_feature_failing_to_give_its_verdict_fails_the_run(tmp_path: Path) -> None:
    """A feature whose outcome() raises is reported and the run exits 1: a verdict that cannot be had is no pass."""
    install(tmp_path, "flaky", FLAKY)
    r = batch(tmp_path, world(tmp_path, plugin='<plugin name="flaky" fail="outcome"/>'))
    assert r.returncode == 1, r.stdout + r.stderr
    assert "  feature 'flaky' disabled (outcome at t=0.600 s): RuntimeError: no verdict" in r.stdout.splitlines()
    assert "Traceback" not in r.stderr


@pytest.fixture
def flaky(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[ModuleType]:
    """The Flaky feature's plugin, registered in this process besides the installed plugins."""
    monkeypatch.delenv(plugins.DISABLE_ENV, raising=False)
    where = site(tmp_path)
    (where / "sigcore_iso_inproc.py").write_text(FLAKY.replace("    sys.exit(7)", "    pass"))
    monkeypatch.syspath_prepend(str(where))
    plugins.reset_for_tests()
    module = importlib.import_module("sigcore_iso_inproc")
    plugins.register_plugin(module, name="iso_inproc")
    yield module
    plugins.reset_for_tests()
    sys.modules.pop("sigcore_iso_inproc", None)


def flaky_sim(tmp_path: Path, attributes: str) -> Simulation:
    return Simulation(parse_world(world(tmp_path, plugin=f'<plugin name="flaky" {attributes}/>')), "mujoco")


def test_failed_feature_is_detached_and_in_the_run_report(flaky: ModuleType, tmp_path: Path) -> None:
    """After its step observer raised, a feature's observers and services are detached and never called again;
    RunReport.feature_failures names it, with the traceback kept."""
    sim = flaky_sim(tmp_path, 'fail="step" at="20"')
    feature = sim.features["flaky"]
    report = run(sim, steps=100, handle_signals=False)
    assert report.steps == 100 and report.stopped_by is None and report.error is None
    [failure] = report.feature_failures
    assert (failure.feature, failure.where, failure.time) == ("flaky", "step observer", pytest.approx(0.04))
    assert "lost [/tmp/data]" in failure.error and "Traceback" in failure.traceback
    assert feature.steps == 20
    sim.send_msg("moderator", "moderator", "hi")
    sim.step(5)
    assert feature.steps == 20 and feature.messages == 0 and "flaky_service" not in sim.features.services


def test_feature_failing_in_a_message_observer_or_reset_is_disabled_once(flaky: ModuleType, tmp_path: Path) -> None:
    """A message observer that raises disables its feature, whose reset is then never called; a reset that raises
    disables the feature once."""
    sim = flaky_sim(tmp_path, 'fail="message"')
    feature = sim.features["flaky"]
    sim.send_msg("moderator", "moderator", "hi")
    sim.step(3)
    sim.reset()
    assert [(f.where, f.error) for f in sim.features.failures] == [("message observer", "KeyError: 'hi'")]
    assert feature.steps == 0 and feature.resets == 0  # the failure was before the first step's observers
    sim = flaky_sim(tmp_path, 'fail="reset"')
    feature = sim.features["flaky"]
    sim.step(2)
    sim.reset()
    sim.reset()
    sim.step(2)
    assert [(f.where, f.error) for f in sim.features.failures] == [("reset", "ValueError: cannot reset")]
    assert feature.resets == 1 and feature.steps == 2


def test_an_observer_no_feature_owns_ends_the_run_with_the_error(sim: Simulation) -> None:
    """A step observer that is not a feature's (the core's, a transport's, a library user's) raising ends the run:
    the report is returned, stopped_by 'error', with the error."""
    def broken(s: Simulation) -> None:
        if s.step_count == 10:
            raise RuntimeError("a bug")

    sim.events.subscribe("step", broken)
    report = run(sim, steps=100, handle_signals=False)
    assert (report.steps, report.stopped_by, report.error) == (10, "error", "RuntimeError: a bug")
    assert report.feature_failures == []


@pytest.mark.slow
def test_a_transport_whose_observer_raises_ends_the_run_with_exit_3(tmp_path: Path) -> None:
    """A transport bug while stepping ends `sigcore run` with the report printed, the error named, exit 3."""
    install(tmp_path, "faulty", FAULTY_TRANSPORT)
    r = sigcore(tmp_path, "run", str(world(tmp_path)), "--transport", "faulty", "--fast", "--steps", "300",
                "--quiet")
    assert r.returncode == 3, r.stdout + r.stderr
    assert "steps:    100" in r.stdout
    assert "stopped:  by an error at t = 0.200 s (not in user code: see the log): RuntimeError: transport bug [/x]" \
        in r.stdout
    assert "the run stopped at t=0.200 s: RuntimeError: transport bug [/x]" in r.stderr  # with its traceback


# ------------------------------------------------------------------ defect 9: slow controllers
@pytest.mark.slow
def test_a_slow_controller_is_reported_by_name(tmp_path: Path) -> None:
    """A controller taking 0.3 s per call, over a 0.1 s budget (3x margin), is warned about by name and reported;
    it keeps running (at 0 s and every 0.1 s up to 0.6 s: 7 calls)."""
    controllers(tmp_path)
    r = batch(tmp_path, world(tmp_path, "iso_controllers:Slow"), "--callback-budget", "0.1")
    assert r.returncode == 0, r.stderr
    assert "controller of agent 'moderator' took" in r.stderr and "over the callback budget of 0.1 s" in r.stderr
    assert r.stderr.count("over the callback budget") == 1  # warned once, counted after
    assert "controller of 'moderator' was slow: 7 callback(s) over the budget of 0.1 s" in r.stdout
    assert calls(tmp_path) == 7 and "steps:    300" in r.stdout


@pytest.mark.slow
def test_a_slow_controller_is_disabled_when_asked(tmp_path: Path) -> None:
    """With --disable-slow-controllers, a controller over the budget is disabled after its first call returned;
    the run goes on to its end."""
    controllers(tmp_path)
    r = batch(tmp_path, world(tmp_path, "iso_controllers:Slow"), "--callback-budget", "0.1",
              "--disable-slow-controllers")
    assert r.returncode == 0, r.stderr
    assert "controller of 'moderator' disabled (on_action at t=0.000 s): took 0." in r.stdout
    assert "s of wall time, over the callback budget of 0.1 s" in r.stdout
    assert calls(tmp_path) == 1 and "steps:    300" in r.stdout


@pytest.mark.slow
def test_a_fast_controller_is_not_reported(tmp_path: Path) -> None:
    """A controller that returns at once is never reported under the default 1 s budget."""
    controllers(tmp_path)
    r = batch(tmp_path, world(tmp_path, "iso_controllers:Counting"))
    assert r.returncode == 0, r.stderr
    assert "budget" not in r.stdout + r.stderr and calls(tmp_path) == 7


@pytest.mark.slow
def test_a_budget_that_is_no_number_of_seconds_is_refused(tmp_path: Path) -> None:
    """--callback-budget nan is refused with exit 2; negative budgets are refused by the library too."""
    r = batch(tmp_path, world(tmp_path), "--callback-budget", "nan")
    assert r.returncode == 2 and "--callback-budget" in r.stderr and "Traceback" not in r.stderr
    with pytest.raises(BudgetError, match=">= 0"):
        CallbackBudget(-1.0)
