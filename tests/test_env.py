"""tools/env.sh: what the environment sees of this machine, said before a command fails on it.

The functions are read by sourcing the script (no Debian root is built or entered): the
Debian root is stood in for by a directory of the test's own.
"""

import subprocess
from pathlib import Path

import pytest
from mpi4py import MPI

PROJECT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="shell functions: one process is enough")


def source_and_run(script: str, *args: str) -> subprocess.CompletedProcess:
    """``script`` (bash) run after sourcing tools/env.sh, with ``args`` as $1, $2, ..."""
    return subprocess.run(
        ["bash", "-c", f'source "{PROJECT}/tools/env.sh"\n{script}', "test", *args],
        capture_output=True,
        text=True,
        cwd=PROJECT,
    )


@pytest.fixture
def machine(tmp_path):
    """A script outside the project, and a stand-in Debian root holding only /bin/sh."""
    script = tmp_path / "my_script.py"
    script.write_text("print('hello')\n")
    root = tmp_path / "root"
    (root / "bin").mkdir(parents=True)
    (root / "bin" / "sh").write_text("")
    return script, root


def invisible(root, cwd_here, cwd_there, command: str) -> list[str]:
    run = source_and_run(
        'ROOT=$1; shift; invisible_paths "$@"',
        str(root),
        str(cwd_here),
        str(cwd_there),
        "/bin/sh",
        "-c",
        command,
    )
    assert run.returncode == 0, run.stderr
    return run.stdout.split()


def test_a_file_outside_the_project_is_found_in_a_command(machine):
    script, root = machine
    here = str(PROJECT)
    # a script named by its absolute path, or after an option's "="
    assert invisible(root, here, here, f"python3 {script}") == [str(script)]
    assert invisible(root, here, here, f"tapecoil run --out={script.parent}") == [str(script.parent)]
    # a relative name read from a directory outside the project, the command run in the project
    assert invisible(root, script.parent, here, "python3 my_script.py") == ["my_script.py"]
    # the project's own files, by any name, and what the root has at the same place are seen
    assert invisible(root, here, here, f"python3 tools/env.sh {PROJECT}/Makefile /bin ./tests") == []
    # the machine's /proc, /sys and /dev are bound into the root
    assert invisible(root, here, here, "cat /proc/cpuinfo /dev/null") == []


def test_a_command_naming_a_file_outside_the_project_is_refused_with_what_to_do(machine):
    script, root = machine
    run = source_and_run(
        'ROOT=$1; shift; check_visible "$@"',
        str(root),
        str(PROJECT),
        str(PROJECT),
        "/bin/sh",
        "-c",
        f"python3 {script}",
    )
    assert run.returncode == 1
    assert f"the command names {script}, outside the project directory {PROJECT}" in run.stderr
    assert "only paths inside the project directory are visible in the environment" in run.stderr
    assert f"Copy what the command needs into the project, e.g. into {PROJECT}/scratch/" in run.stderr
    ok = source_and_run(
        'ROOT=$1; shift; check_visible "$@"', str(root), str(PROJECT), str(PROJECT), "python3", "tools/env.sh"
    )
    assert ok.returncode == 0, ok.stderr


def test_entering_a_directory_the_environment_cannot_see_says_so(tmp_path):
    """The step inside the root that enters the command's directory: a clear refusal where it
    is missing there, the command run where it is not."""
    missing = tmp_path / "nowhere"
    run = source_and_run('sh -c "$ENTER" sh "$1" "$2" pwd', str(missing), str(PROJECT))
    assert run.returncode == 1
    assert (
        f"{missing} is not visible in the environment: only paths inside the project directory" in run.stderr
    )
    assert f"e.g. into {PROJECT}/scratch/" in run.stderr
    run = source_and_run('sh -c "$ENTER" sh "$1" "$2" pwd', str(tmp_path), str(PROJECT))
    assert run.returncode == 0 and run.stdout.strip() == str(tmp_path)
