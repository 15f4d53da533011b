"""Files the user names are written where they are: a FIFO, a device or a symlink given as an
output stays what it is (never replaced by a renamed regular file), a write error (ENOSPC, as
/dev/full gives) is a message and a non-zero exit, and ``-`` is standard output — for every
command that writes a user's path (``compare --json/--csv``, ``export --csv/--parquet``,
``truth --csv``). Every special file is made inside the test's temporary directory."""

import io
import json
import os
import stat
import threading

import pandas as pd
import pytest

from dalembert import output
from dalembert.harness.cli import main
from stores import small_store

# How long a reader thread may wait for the writer to open a FIFO; a generous bound against a
# hang (the write itself takes milliseconds), never a timing the test asserts on.
FIFO_JOIN_S = 120.0


@pytest.fixture(scope="module")
def rod(tmp_path_factory):
    return small_store(tmp_path_factory.mktemp("rod"), cases=("pivoted_rod",), integrators=("rk4",), dts=(1e-2,),
                       t_final=0.2)


def _full_device(path):
    """A character device with /dev/full's numbers (1, 7) at ``path``: every write fails with ENOSPC."""
    try:
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 7))
    except PermissionError:
        pytest.skip("mknod of a character device is not permitted here (needs root or CAP_MKNOD)")
    try:  # a filesystem mounted nodev refuses to open it: no device to test against then
        os.close(os.open(path, os.O_WRONLY))
    except PermissionError:
        pytest.skip(f"{os.path.dirname(path)} does not allow devices (nodev)")
    return path


class _FifoReader:
    """Reads a FIFO from a thread until its writer closes it (opening a FIFO blocks until both ends are open)."""

    def __init__(self, path):
        os.mkfifo(path)
        self.path, self.data = path, None
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self):
        with open(self.path, "rb") as fh:
            self.data = fh.read()

    def result(self):
        self.thread.join(FIFO_JOIN_S)
        assert not self.thread.is_alive(), "nothing opened the FIFO for writing"
        assert stat.S_ISFIFO(os.lstat(self.path).st_mode), "the FIFO was replaced"
        return self.data


# ------------------------------------------------------------------ the module itself
def test_a_fifo_is_written_not_replaced(tmp_path):
    reader = _FifoReader(tmp_path / "pipe")
    output.write(tmp_path / "pipe", "a,b\n1,2\n", "--csv")
    assert reader.result() == b"a,b\n1,2\n"


def test_a_symlink_s_target_is_written_and_the_link_stays(tmp_path):
    target = tmp_path / "target.json"
    target.write_text("old")
    (tmp_path / "link.json").symlink_to(target)
    output.write(tmp_path / "link.json", b"new", "--json")
    assert os.path.islink(tmp_path / "link.json") and target.read_bytes() == b"new"


def test_a_full_device_is_an_error_naming_the_flag_and_stays_a_device(tmp_path):
    full = _full_device(str(tmp_path / "full"))
    with pytest.raises(output.OutputError, match=r"--json .*full: cannot write it \(No space left on device\)"):
        output.write(full, "x" * 100, "--json")
    assert stat.S_ISCHR(os.lstat(full).st_mode)


def test_a_file_that_cannot_be_written_is_not_left_half_made(tmp_path, monkeypatch):
    """A new regular file whose write fails (the disk filled up) is removed; the error names the flag."""
    class Full(io.StringIO):
        def write(self, data):
            raise OSError(28, "No space left on device")

    def opened(path, mode, **kwargs):
        open(path, mode, **kwargs).close()  # the file is made, as open() makes it, then every write fails
        return Full()

    monkeypatch.setattr(output, "open", opened, raising=False)
    with pytest.raises(output.OutputError, match=r"--csv .*new.csv: cannot write it \(No space left"):
        output.write(tmp_path / "new.csv", "x", "--csv")
    assert not (tmp_path / "new.csv").exists()


def test_dash_is_standard_output_text_and_bytes(capsysbinary):
    output.write("-", "text\n", "--csv")
    output.write("-", b"\x00bytes", "--parquet")
    assert capsysbinary.readouterr().out == b"text\n\x00bytes"


@pytest.mark.parametrize("name,words", [("", "empty"), ("missing/x.csv", "no directory"), (".", "a directory")])
def test_outputs_that_cannot_be_written_are_refused_before_anything_runs(tmp_path, name, words):
    with pytest.raises(output.OutputError, match=words):
        output.check(str(tmp_path / name) if name else name, "--csv")
    output.check("-", "--csv")  # standard output is always there


# ------------------------------------------------------------------ the commands
def test_compare_json_into_a_fifo_a_device_and_a_symlink(rod, tmp_path, capsys):
    reader = _FifoReader(tmp_path / "pipe")
    assert main(["compare", rod.path, rod.path, "--json", str(tmp_path / "pipe")]) == 0
    assert json.loads(reader.result())["counts"]["same"] == 1
    target = tmp_path / "t.csv"
    (tmp_path / "link.csv").symlink_to(target)
    assert main(["compare", rod.path, rod.path, "--csv", str(tmp_path / "link.csv")]) == 0
    assert os.path.islink(tmp_path / "link.csv") and target.read_text().startswith("case,params")
    full = _full_device(str(tmp_path / "full"))
    capsys.readouterr()
    assert main(["compare", rod.path, rod.path, "--json", full]) == 2
    err = capsys.readouterr().err
    assert "--json" in err and "No space left on device" in err and "wrote" not in err
    assert stat.S_ISCHR(os.lstat(full).st_mode)


def test_compare_json_to_standard_output(rod, capsys):
    assert main(["compare", rod.path, rod.path, "--json", "-"]) == 0
    assert json.loads(capsys.readouterr().out)["counts"]["same"] == 1  # the JSON alone, not the text too


def test_export_csv_to_standard_output_and_parquet_into_a_fifo(rod, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["export", rod.path, "--all", "--csv", "-"]) == 0
    captured = capsys.readouterr()
    assert not (tmp_path / "-").exists()
    df = pd.read_csv(io.StringIO(captured.out))
    assert set(df.kind) == {"body", "joint", "reaction_force"} and "wrote standard output" in captured.err
    reader = _FifoReader(tmp_path / "pipe")
    assert main(["export", rod.path, "--all", "--parquet", str(tmp_path / "pipe")]) == 0
    assert main(["export", rod.path, "--all", "--parquet", str(tmp_path / "plain.parquet")]) == 0
    assert reader.result() == (tmp_path / "plain.parquet").read_bytes()


def test_export_to_a_full_device_fails(rod, tmp_path, capsys):
    full = _full_device(str(tmp_path / "full"))
    assert main(["export", rod.path, "--all", "--csv", full]) == 2
    assert "--csv" in capsys.readouterr().err and stat.S_ISCHR(os.lstat(full).st_mode)


def test_truth_csv_to_standard_output_a_fifo_and_a_full_device(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = ["truth", "particle_box", "--param", "t_final=0.1"]
    assert main(argv + ["--csv", "-"]) == 0
    captured = capsys.readouterr()
    assert captured.out.startswith("t,body,") and "wrote standard output" in captured.err
    assert not (tmp_path / "-").exists()
    reader = _FifoReader(tmp_path / "pipe")
    assert main(argv + ["--csv", str(tmp_path / "pipe")]) == 0
    assert reader.result().decode() == captured.out
    full = _full_device(str(tmp_path / "full"))
    assert main(argv + ["--csv", full]) == 2
    assert "No space left on device" in capsys.readouterr().err and stat.S_ISCHR(os.lstat(full).st_mode)
