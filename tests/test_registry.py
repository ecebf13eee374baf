"""Plugin discovery through the fsi_lab entry-point group, with a real installed distribution."""

import pytest
from support import cli, cli_json

from fsi_lab.errors import PluginError
from fsi_lab.registry import load_registry

BUILT_IN_INSTRUMENTS = {"inprocess-source", "inprocess-amplifier", "inprocess-vibrometer",
                        "inprocess-acquisition"}


def _by_name(plugins):
    return {p["name"]: p for p in plugins}


def test_built_ins_are_loaded_through_entry_points(registry):
    assert BUILT_IN_INSTRUMENTS <= set(registry.names("instrument"))
    assert {"step", "ramp-derivative"} <= set(registry.names("excitation"))
    record = next(r for r in registry.records if r.name == "step")
    assert (record.distribution, record.status, record.kind) == ("fsi-lab", "loaded", "excitation")


def test_external_distribution_is_discovered_and_broken_ones_isolated(example_plugin_dir):
    data, proc = cli_json("plugins", env={"PYTHONPATH": str(example_plugin_dir)})
    assert proc.returncode == 0, proc.stderr
    plugins = _by_name(data["plugins"])
    for name in ("chirp", "rms", "crossings"):
        assert plugins[name]["status"] == "loaded"
        assert plugins[name]["distribution"] == "fsi-lab-example-plugin"
        assert plugins[name]["version"] == "1.2.3"
    assert plugins["chirp"]["kind"] == "excitation"
    assert plugins["rms"]["kind"] == "analysis"
    chirp_params = {p["name"]: p for p in plugins["chirp"]["params"]}
    assert chirp_params["amplitude"]["unit"] == "V" and chirp_params["amplitude"]["maximum"] == 5.0

    broken = plugins["example-broken"]
    assert broken["status"] == "failed"
    assert "ModuleNotFoundError" in broken["error"]
    assert "fsi_lab_example_missing_dependency" in broken["error"]
    bad = plugins["example-bad-contract"]
    assert bad["status"] == "invalid"
    assert "expected ExcitationPlugin" in bad["error"]
    # the rest keep working
    assert BUILT_IN_INSTRUMENTS <= {n for n, p in plugins.items() if p["status"] == "loaded"}
    # a plugin that did not load is named as left out; a bad contribution as left out alone
    assert "[warning] plugin example-broken (fsi-lab-example-plugin) not loaded: " \
           "ModuleNotFoundError" in proc.stderr
    assert "[warning] plugin example-bad-contract (fsi-lab-example-plugin): breaks the " \
           "excitation contract" in proc.stderr


def test_external_commands_are_added_through_the_hook_listed_and_run(example_plugin_dir,
                                                                      tmp_path):
    env = {"PYTHONPATH": str(example_plugin_dir)}
    data, proc = cli_json("plugins", env=env)
    commands = _by_name(data["commands"])
    assert commands["bench"]["distribution"] == "fsi-lab"
    count = commands["example-count"]
    assert (count["status"], count["distribution"], count["version"], count["help"]) == \
        ("loaded", "fsi-lab-example-plugin", "1.2.3", "count the lines of a file")
    # a hook that fails (here: a command named like one of fsi-lab's) is reported, named
    clash = commands["example-bad-command"]
    assert clash["status"] == "failed"
    assert "fsi_lab_addcommands() failed" in clash["error"]
    assert "the command 'run' exists already (at " in clash["error"]
    assert "bad_command.py:13)" in clash["error"]  # the plugin's line
    three_lines = tmp_path / "three.txt"
    three_lines.write_text("a\nb\nc\n")
    proc = cli("example-count", str(three_lines), env=env)
    assert proc.returncode == 0 and proc.stdout.strip() == "3", proc.stderr
    assert "commands of plugin example-bad-command (fsi-lab-example-plugin) skipped" \
        in proc.stderr
    # fsi-lab run is still fsi-lab's
    assert "usage: fsi-lab run" in cli("run", "--help", env=env).stdout


def test_a_command_of_the_old_entry_point_group_is_refused_saying_what_to_write(
        example_plugin_dir, tmp_path):
    env = {"PYTHONPATH": str(example_plugin_dir)}
    data, _ = cli_json("plugins", env=env)
    legacy = _by_name(data["commands"])["example-legacy-count"]
    assert legacy["status"] == "refused"
    for words in ("'fsi_lab.commands' entry-point group, which fsi-lab no longer reads",
                  "fsi_lab_addcommands(subparsers)", "COMMAND.add_to(subparsers)"):
        assert words in legacy["error"]
    proc = cli("example-legacy-count", "x.txt", env=env)
    assert proc.returncode == 2 and proc.stdout == ""
    assert ("fsi-lab: error: fsi-lab example-legacy-count: fsi-lab-example-plugin 1.2.3 "
            "declared in the 'fsi_lab.commands' entry-point group") in proc.stderr


def test_every_hook_is_called_through_the_plugin_manager(with_example_plugin, monkeypatch):
    """No implementation is called around pluggy: with the manager's hook calls monitored,
    loading the plugins, adding their commands, summary text, the default chain and the views
    are each seen as calls of the hook."""
    import argparse

    registry = load_registry()
    called = []
    registry.manager.add_hookcall_monitoring(lambda name, impls, kwargs: called.append(name),
                                             lambda outcome, name, impls, kwargs: None)
    registry.add_commands(argparse.ArgumentParser().add_subparsers())
    registry.summary_texts("tip", {"components": []})
    registry.default_chain_names()
    registry.views()
    assert {"fsi_lab_addcommands", "fsi_lab_summary_lines", "fsi_lab_default_chain",
            "fsi_lab_addviews"} <= set(called)
    from types import ModuleType

    from fsi_lab.hookspecs import hookimpl
    from fsi_lab.registry import add_plugin

    module = ModuleType("more_excitations")
    module.fsi_lab_excitations = hookimpl(lambda: [])
    add_plugin(registry, module, "more-excitations")
    assert "fsi_lab_excitations" in called


def test_every_record_has_the_documented_keys(example_plugin_dir):
    data, _ = cli_json("plugins", env={"PYTHONPATH": str(example_plugin_dir)})
    for plugin in data["plugins"]:
        assert {"name", "kind", "version", "distribution", "status", "error"} <= set(plugin)
        assert plugin["kind"] in ("instrument", "excitation", "analysis", None)


def test_autoload_can_be_disabled_with_an_allow_list(with_example_plugin, monkeypatch):
    monkeypatch.setenv("FSI_LAB_DISABLE_PLUGIN_AUTOLOAD", "1")
    monkeypatch.setenv("FSI_LAB_PLUGINS", "example,step")
    registry = load_registry()
    assert registry.names("excitation") == ["chirp", "step"]
    assert registry.names("instrument") == []
    disabled = {r.entry_point for r in registry.records if r.status == "disabled"}
    assert {"inprocess", "ramp-derivative", "example-broken"} <= disabled


def test_a_disabled_plugin_is_reported_as_unknown_with_the_choices(with_example_plugin,
                                                                     monkeypatch):
    monkeypatch.setenv("FSI_LAB_DISABLE_PLUGIN_AUTOLOAD", "1")
    monkeypatch.setenv("FSI_LAB_PLUGINS", "step")
    registry = load_registry()
    with pytest.raises(PluginError, match="unknown excitation plugin 'chirp'; installed "
                                          "excitation plugins: step"):
        registry.get("excitation", "chirp")


def test_a_deferred_function_is_imported_on_its_first_call():
    from fsi_lab.contract import Deferred

    deferred = Deferred("fsi_lab.lti:interpolate")
    assert callable(deferred) and deferred.load().__name__ == "interpolate"
    assert list(deferred([1.0, 2.0], 1)) == [1.0, 2.0]
    with pytest.raises(ValueError, match="package.module:function"):
        Deferred("fsi_lab.lti.interpolate")
    with pytest.raises(ModuleNotFoundError):
        Deferred("fsi_lab.no_such_module:run")()


def test_built_in_analyses_run_their_work_through_deferred_modules(registry):
    from fsi_lab.contract import Deferred

    for name in registry.names("analysis"):
        run = registry.get("analysis", name).run
        if registry.version_of("analysis", name).startswith("fsi-lab "):
            assert isinstance(run, Deferred), name
            assert callable(run.load()), name


def test_a_plugin_of_commands_or_views_only_is_listed_with_its_hooks():
    data, _ = cli_json("plugins")
    plugins = _by_name(data["plugins"])
    assert (plugins["analysis-views"]["kind"], plugins["analysis-views"]["status"],
            plugins["analysis-views"]["hooks"]) == (None, "loaded", ["fsi_lab_addviews"])
    assert plugins["scaffold"]["hooks"] == ["fsi_lab_addcommands"]
    assert plugins["hvd"]["hooks"] == ["fsi_lab_analyses", "fsi_lab_default_chain",
                                       "fsi_lab_summary_lines"]
