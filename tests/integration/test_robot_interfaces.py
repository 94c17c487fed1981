"""Robot interfaces are loaded by name from a skill process's configuration (a TOML file or
--interface), and a skill that needs one the process lacks fails naming it."""

import sys

from test_skills import LIBS, cli, mgr_binary


def skills_process(sandbox, name, *args):
    return sandbox.start(name, [sys.executable, "-m", "skillbus.cli", "skills-process", *args],
                         env={"PYTHONPATH": str(LIBS)})


def registered(proc, timeout=30):
    proc.wait_for("registered", timeout)


def test_an_interface_from_the_configuration_file_reaches_the_skill(sandbox, tmp_path):
    conf = tmp_path / "skills.toml"
    conf.write_text('name = "probed"\nlibrary = ["probe_skills"]\n\n'
                    '[interfaces]\nprobe = "probe_interface:left-camera"\n')
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    registered(skills_process(sandbox, "probed", "--config", str(conf)))
    rc, out, _ = cli(sandbox, "run", "ReadProbe", "--timeout", "20")
    assert rc == 0 and "probe says left-camera" in out, out


def test_the_command_line_overrides_the_file_and_a_missing_interface_is_named(sandbox, tmp_path):
    conf = tmp_path / "skills.toml"
    conf.write_text('library = ["probe_skills"]\n[interfaces]\nprobe = "probe_interface:from-file"\n')
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    registered(skills_process(sandbox, "p1", "--config", str(conf), "--name", "p1",
                              "--interface", "probe=probe_interface:from-cli"))
    rc, out, _ = cli(sandbox, "run", "ReadProbe", "--timeout", "20")
    assert rc == 0 and "probe says from-cli" in out, out


def test_a_skill_without_its_interface_fails_naming_it(sandbox):
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    registered(skills_process(sandbox, "bare", "--name", "bare", "--library", "probe_skills"))
    rc, out, _ = cli(sandbox, "run", "ReadProbe", "--timeout", "20")
    assert rc == 1 and "this skill process has no probe interface (it has: none)" in out, out


def test_an_interface_that_cannot_load_stops_the_process_naming_it(sandbox, tmp_path):
    p = skills_process(sandbox, "broken", "--name", "broken", "--library", "probe_skills",
                       "--interface", "probe=no_such_module")
    assert sandbox.wait(p, 30) == 2
    assert "interface probe: cannot import no_such_module" in p.stderr(), p.stderr()
    conf = tmp_path / "bad.toml"
    conf.write_text('name = "x"\nlibraries = ["probe_skills"]\n')
    q = skills_process(sandbox, "badconf", "--config", str(conf))
    assert sandbox.wait(q, 30) == 2
    assert "unknown setting(s) libraries" in q.stderr(), q.stderr()
