"""Plugin discovery and registries, with fake distributions (a ``*.dist-info`` on ``sys.path``)."""

from __future__ import annotations

import json
import logging
import subprocess
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

import sigcore
from sigcore import plugins
from sigcore.agent import Controller
from sigcore.agent.controller import resolve_controller
from sigcore.backend import Backend

FAKE_PREFIX = "sigcore_fake_"

PRELUDE = '''\
import sigcore
from sigcore.agent import Controller
from sigcore.backend import Backend
from sigcore.feature import Feature

CALLS = []


def stub_backend(name):
    """A concrete Backend subclass called ``name`` whose methods do nothing."""
    body = {m: (lambda self, *args, **kwargs: None) for m in Backend.__abstractmethods__}
    return type("Stub_" + name, (Backend,), {"name": name, "__module__": __name__, **body})
'''


def stub_backend(name: str) -> type[Backend]:
    """A concrete backend class called ``name`` whose methods do nothing."""
    body: dict[str, Any] = {m: (lambda self, *args, **kwargs: None) for m in Backend.__abstractmethods__}
    return type(f"Stub_{name}", (Backend,), {"name": name, "__module__": __name__, **body})


@pytest.fixture(autouse=True)
def fresh_registry(fresh_plugins: None) -> Iterator[None]:
    """Every test starts with no plugin loaded, and leaves the next lookup to rediscover the real ones."""
    yield
    for name in [m for m in sys.modules if m.startswith(FAKE_PREFIX)]:
        del sys.modules[name]


@pytest.fixture
def site(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A directory on ``sys.path`` where fake distributions are written."""
    path = tmp_path / "site"
    path.mkdir()
    monkeypatch.syspath_prepend(str(path))
    return path


def fake_dist(site: Path, dist: str, version: str, entry_points: dict[str, str],
              modules: dict[str, str]) -> None:
    """Write a distribution as pip installs one: modules and a ``.dist-info`` with ``entry_points.txt``."""
    info = site / f"{dist.replace('-', '_')}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n")
    eps = "".join(f"{name} = {target}\n" for name, target in entry_points.items())
    (info / "entry_points.txt").write_text(f"[{plugins.GROUP}]\n{eps}")
    for module, source in modules.items():
        (site / f"{module}.py").write_text(PRELUDE + textwrap.dedent(source))


GOOD = '''
@sigcore.hookimpl
def sigcore_register_backends(register):
    CALLS.append("backends")
    register(stub_backend("fakephys"))


@sigcore.hookimpl
def sigcore_register_features(register):
    class Counter(Feature):
        name = "fakefeat"

        def __init__(self, sim, config):
            pass

    register(Counter)


class Greeter(Controller):
    pass


@sigcore.hookimpl
def sigcore_register_controllers(register):
    register("fake.greeter", Greeter)
'''


def good_dist(site: Path) -> None:
    fake_dist(site, "sigcore-fake-good", "1.2.3", {"good": "sigcore_fake_good"}, {"sigcore_fake_good": GOOD})


def info(name: str) -> plugins.PluginInfo:
    return next(i for i in plugins.plugin_infos() if i.name == name)


# ------------------------------------------------------------------ discovery
def test_fake_distribution_is_discovered_with_what_it_provides(site: Path) -> None:
    """A sigcore entry point is loaded and listed with distribution, version and what it provides."""
    good_dist(site)
    good = info("good")
    assert (good.distribution, good.version, good.module, good.error) == (
        "sigcore-fake-good", "1.2.3", "sigcore_fake_good", None)
    assert good.provides == {"backend": ("fakephys",), "feature": ("fakefeat",),
                             "controller": ("fake.greeter",)}
    assert good.provided() == ["backend fakephys", "feature fakefeat", "controller fake.greeter"]
    assert plugins.get_backend("fakephys").__module__ == "sigcore_fake_good"
    assert plugins.features()["fakefeat"].name == "fakefeat"


def test_nothing_is_loaded_at_import() -> None:
    """Importing sigcore and sigcore.plugins loads no plugin; the first lookup does."""
    code = ("import sys, sigcore, sigcore.plugins as p; "
            "print(p._state.loaded, p.pm.get_plugins() == set(), 'sigcore_backend_mujoco' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    assert out.stdout.split() == ["False", "True", "False"]


def test_load_plugins_is_idempotent(site: Path) -> None:
    """A second load_plugins, and any number of lookups, load nothing again and call no hook again."""
    good_dist(site)
    first = plugins.load_plugins()
    registered = plugins.pm.get_plugins()
    assert plugins.load_plugins() == first
    for _ in range(3):
        plugins.backends()
        plugins.get_backend("fakephys")
    assert plugins.pm.get_plugins() == registered
    assert sys.modules["sigcore_fake_good"].CALLS == ["backends"]


def test_disable_env_skips_entry_points(site: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """With SIGCORE_DISABLE_PLUGIN_AUTOLOAD set, no entry point loads; register_plugin still works."""
    good_dist(site)
    monkeypatch.setenv(plugins.DISABLE_ENV, "1")
    assert plugins.plugin_infos() == []
    assert plugins.backends() == {}
    assert "sigcore_fake_good" not in sys.modules
    plugins.register_plugin(SimpleNamespace(sigcore_register_backends=backends_hook(stub_backend("manual"))),
                            name="manual")
    assert list(plugins.backends()) == ["manual"]


def test_reset_for_tests_rediscovers_entry_points(site: Path) -> None:
    """After reset_for_tests the next lookup discovers the installed plugins again."""
    good_dist(site)
    assert "fakephys" in plugins.backends()
    plugins.reset_for_tests()
    assert plugins.pm.get_plugins() == set()
    assert "fakephys" in plugins.backends()


# ------------------------------------------------------------------ broken plugins
def test_plugin_failing_to_import_is_reported_and_others_load(site: Path,
                                                              caplog: pytest.LogCaptureFixture) -> None:
    """A plugin whose module raises ImportError is recorded by name, distribution and version; others load."""
    good_dist(site)
    fake_dist(site, "sigcore-fake-broken", "0.4", {"broken": "sigcore_fake_broken"},
              {"sigcore_fake_broken": 'raise ImportError("needs libfoo")\n'})
    broken = info("broken")
    assert (broken.distribution, broken.version, broken.provides) == ("sigcore-fake-broken", "0.4", {})
    assert broken.error == "importing 'sigcore_fake_broken' raised ImportError: needs libfoo"
    assert not broken.loaded and not plugins.pm.has_plugin("broken")
    assert info("good").loaded and "fakephys" in plugins.backends()
    warning = next(r.getMessage() for r in caplog.records if "'broken'" in r.getMessage())
    assert "sigcore-fake-broken 0.4" in warning and "needs libfoo" in warning


def test_plugin_whose_hook_raises_is_disabled_whole(site: Path, caplog: pytest.LogCaptureFixture) -> None:
    """A registration hook that raises disables its plugin (none of its names register); others still load."""
    good_dist(site)
    fake_dist(site, "sigcore-fake-raising", "2.0", {"raising": "sigcore_fake_raising"},
              {"sigcore_fake_raising": '''
        @sigcore.hookimpl
        def sigcore_register_backends(register):
            register(stub_backend("halfway"))

        @sigcore.hookimpl
        def sigcore_register_features(register):
            raise RuntimeError("no licence key")
        '''})
    raising = info("raising")
    assert raising.error == "sigcore_register_features raised RuntimeError: no licence key"
    assert raising.distribution == "sigcore-fake-raising" and raising.version == "2.0"
    assert "halfway" not in plugins.backends() and "fakephys" in plugins.backends()
    assert not plugins.pm.has_plugin("raising")
    assert any("'raising' (sigcore-fake-raising 2.0)" in r.getMessage() for r in caplog.records)


@pytest.mark.parametrize(("body", "error"), [
    ("register(object)", "backend <class 'object'> is not a subclass of sigcore.backend.Backend"),
    ("register(type('Half', (Backend,), {'name': 'half'}))",
     "backend Half does not implement add_joint_torque, apply_wrench, attach"),
    ("register(stub_backend(''))", "backend Stub_ needs a non-empty name, got ''"),
])
def test_invalid_registration_disables_the_plugin(site: Path, body: str, error: str) -> None:
    """register() refuses a non-Backend, an abstract class or a nameless one, and says which and why."""
    fake_dist(site, "sigcore-fake-bad", "1.0", {"bad": "sigcore_fake_bad"}, {"sigcore_fake_bad": f'''
        @sigcore.hookimpl
        def sigcore_register_backends(register):
            {body}
        '''})
    bad = info("bad")
    assert bad.error is not None
    assert bad.error.startswith("sigcore_register_backends raised ") and error in bad.error


def test_misspelled_hook_is_reported_with_a_suggestion(site: Path) -> None:
    """A hookimpl without a hookspec (a typo) disables the plugin with 'did you mean'."""
    fake_dist(site, "sigcore-fake-typo", "1.0", {"typo": "sigcore_fake_typo"}, {"sigcore_fake_typo": '''
        @sigcore.hookimpl
        def sigcore_register_backend(register):
            register(stub_backend("typo"))
        '''})
    assert info("typo").error == ("unknown hook 'sigcore_register_backend' "
                                  "(did you mean 'sigcore_register_backends'?)")
    assert "typo" not in plugins.backends()


def test_hook_without_marker_is_warned_about(site: Path, caplog: pytest.LogCaptureFixture) -> None:
    """A function named like a hook but without @sigcore.hookimpl is ignored with a warning."""
    fake_dist(site, "sigcore-fake-plain", "1.0", {"plain": "sigcore_fake_plain"}, {"sigcore_fake_plain": '''
        def sigcore_register_backends(register):
            register(stub_backend("plain"))
        '''})
    assert info("plain").loaded and info("plain").provides == {}
    assert any("'plain' defines sigcore_register_backends without @sigcore.hookimpl" in r.getMessage()
               for r in caplog.records)


# ------------------------------------------------------------------ duplicates
def test_duplicate_name_first_plugin_wins_and_warning_names_both(site: Path,
                                                                 caplog: pytest.LogCaptureFixture) -> None:
    """Two plugins registering backend 'dup': the first loaded keeps it; the warning names both plugins."""
    source = 'sigcore_register_backends = sigcore.hookimpl(lambda register: register(stub_backend("dup")))\n'
    fake_dist(site, "sigcore-fake-aa", "1.0", {"aa": "sigcore_fake_aa"}, {"sigcore_fake_aa": source})
    fake_dist(site, "sigcore-fake-bb", "2.0", {"bb": "sigcore_fake_bb"}, {"sigcore_fake_bb": source})
    assert plugins.get_backend("dup").__module__ == "sigcore_fake_aa"
    assert info("aa").provides == {"backend": ("dup",)} and info("bb").provides == {}
    assert info("bb").loaded
    [warning] = [r.getMessage() for r in caplog.records if "'dup'" in r.getMessage()]
    assert warning == ("backend 'dup' of sigcore plugin 'bb' (sigcore-fake-bb 2.0) is ignored: "
                       "plugin 'aa' (sigcore-fake-aa 1.0) registered it first")


def test_duplicate_entry_point_name_is_reported(site: Path) -> None:
    """Two distributions declaring the same entry-point name: the second is disabled, naming the first."""
    fake_dist(site, "sigcore-fake-one", "1.0", {"same": "sigcore_fake_one"}, {"sigcore_fake_one": ""})
    fake_dist(site, "sigcore-fake-two", "1.0", {"same": "sigcore_fake_two"}, {"sigcore_fake_two": ""})
    same = [i for i in plugins.plugin_infos() if i.name == "same"]
    assert [(i.distribution, i.error) for i in same] == [
        ("sigcore-fake-one", None),
        ("sigcore-fake-two",
         "entry-point name 'same' is already used by 'same' (sigcore-fake-one 1.0); rename one"),
    ]


# ------------------------------------------------------------------ lookups
def backends_hook(*classes: type[Backend]) -> Any:
    """A ``sigcore_register_backends`` hookimpl registering ``classes``."""

    @sigcore.hookimpl
    def sigcore_register_backends(register: Any) -> None:
        for cls in classes:
            register(cls)

    return sigcore_register_backends


def test_get_backend_unknown_name_lists_available(monkeypatch: pytest.MonkeyPatch) -> None:
    """get_backend('bulet') says it is not registered, lists the registered backends and suggests one."""
    monkeypatch.setenv(plugins.DISABLE_ENV, "1")
    hook = backends_hook(stub_backend("mujoco"), stub_backend("bullet"))
    hooks = SimpleNamespace(sigcore_register_backends=hook)
    plugins.register_plugin(hooks, name="engines")
    with pytest.raises(plugins.PluginError) as e:
        plugins.get_backend("bulet")
    assert str(e.value) == ("backend 'bulet' is not registered; available: bullet, mujoco "
                            "(did you mean 'bullet'?)")
    assert (e.value.kind, e.value.name, e.value.available) == ("backend", "bulet", ["bullet", "mujoco"])
    assert isinstance(e.value, LookupError)


def test_unknown_name_error_mentions_failed_plugins(site: Path) -> None:
    """When a lookup fails, plugins that failed to load are named with their error (they may be the cause)."""
    fake_dist(site, "sigcore-backend-fakephys", "0.9", {"fakephys": "sigcore_fake_missing_dep"},
              {"sigcore_fake_missing_dep": "import sigcore_fake_no_such_module\n"})
    with pytest.raises(plugins.PluginError) as e:
        plugins.get_backend("fakephys")
    assert ("plugins that failed to load: 'fakephys' (sigcore-backend-fakephys 0.9): importing "
            "'sigcore_fake_missing_dep' raised ModuleNotFoundError: "
            "No module named 'sigcore_fake_no_such_module'") in str(e.value)


def test_get_transport_unknown_with_none_installed(monkeypatch: pytest.MonkeyPatch) -> None:
    """With no transport installed the error says so and how to find one."""
    monkeypatch.setenv(plugins.DISABLE_ENV, "1")
    with pytest.raises(plugins.PluginError, match=r"^transport 'ros2' is not registered; available: none \("):
        plugins.get_transport("ros2")


def test_controller_resolves_by_short_name(site: Path) -> None:
    """A controller registered through sigcore_register_controllers resolves by its short name."""
    good_dist(site)
    cls = resolve_controller("fake.greeter", plugins.controllers())
    assert issubclass(cls, Controller) and cls.__module__ == "sigcore_fake_good"


# ------------------------------------------------------------------ in-process plugins
def test_register_plugin_refuses_broken_ones(monkeypatch: pytest.MonkeyPatch) -> None:
    """register_plugin raises PluginLoadError for a taken name or a raising hook, and keeps nothing of it."""
    monkeypatch.setenv(plugins.DISABLE_ENV, "1")
    ok = plugins.register_plugin(SimpleNamespace(sigcore_register_backends=backends_hook(stub_backend("x"))),
                                 name="ok")
    assert (ok.distribution, ok.provides) == ("", {"backend": ("x",)})
    assert ok.describe() == "'ok' (in-process)"
    with pytest.raises(plugins.PluginLoadError, match="a plugin named 'ok' is already registered"):
        plugins.register_plugin(SimpleNamespace(), name="ok")

    @sigcore.hookimpl
    def sigcore_register_transports(register: Any) -> None:
        raise ValueError("bad config")

    with pytest.raises(plugins.PluginLoadError) as e:
        plugins.register_plugin(SimpleNamespace(sigcore_register_transports=sigcore_register_transports),
                                name="bad")
    assert e.value.info.error == "sigcore_register_transports raised ValueError: bad config"
    assert not plugins.pm.has_plugin("bad") and [i.name for i in plugins.plugin_infos()] == ["ok"]


def test_plugins_registered_directly_with_pluggy_are_followed(monkeypatch: pytest.MonkeyPatch) -> None:
    """pm.register / pm.unregister behind the registry's back are seen by the next lookup."""
    monkeypatch.setenv(plugins.DISABLE_ENV, "1")
    assert plugins.backends() == {}
    hooks = SimpleNamespace(sigcore_register_backends=backends_hook(stub_backend("direct")))
    plugins.pm.register(hooks, name="direct")
    assert list(plugins.backends()) == ["direct"]
    assert info("direct").provides == {"backend": ("direct",)}
    plugins.pm.unregister(name="direct")
    assert plugins.backends() == {} and plugins.plugin_infos() == []


def test_add_commands_isolates_a_raising_plugin(monkeypatch: pytest.MonkeyPatch,
                                                caplog: pytest.LogCaptureFixture) -> None:
    """A plugin whose sigcore_register_commands raises is logged by name; the others still add commands."""
    monkeypatch.setenv(plugins.DISABLE_ENV, "1")
    added: list[str] = []

    @sigcore.hookimpl
    def adds(cli: list[str]) -> None:
        cli.append("hello")

    @sigcore.hookimpl
    def raises(cli: list[str]) -> None:
        raise RuntimeError("typer too old")

    plugins.register_plugin(SimpleNamespace(sigcore_register_commands=raises), name="raises")
    plugins.register_plugin(SimpleNamespace(sigcore_register_commands=adds), name="adds")
    with caplog.at_level(logging.WARNING):
        plugins.add_commands(added)
    assert added == ["hello"]
    assert any("'raises' (in-process): sigcore_register_commands raised RuntimeError: typer too old"
               in r.getMessage() for r in caplog.records)


def test_plugin_infos_are_json_serialisable(site: Path) -> None:
    """plugin_infos() holds plain data that `sigcore plugins --json` could print."""
    good_dist(site)
    from dataclasses import asdict

    data = json.loads(json.dumps([asdict(i) for i in plugins.plugin_infos() if i.name == "good"]))
    assert data[0]["provides"]["backend"] == ["fakephys"]


def test_docs_list_every_hook() -> None:
    """docs/plugins.md's hook table names every hookspec of sigcore.hookspecs."""
    doc = (Path(__file__).parent.parent / "docs" / "plugins.md").read_text()
    table = [line for line in doc.splitlines() if line.startswith("| `sigcore_")]
    documented = {line.split("`")[1].split("(")[0] for line in table}
    assert documented == set(plugins._SPECS)
