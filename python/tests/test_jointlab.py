"""The Python module against the command line's output on the same input, and its error paths.

Run by `make test` (ctest runs pytest with PYTHONPATH=build/python). Every call is compared with
the CSV the program writes for the same input: within 1e-9 relative (the CSV keeps 10
significant digits, so up to 5e-10 of rounding).
"""
import csv
import json
import os
import pathlib
import pickle
import signal
import subprocess
import threading

import numpy as np
import pytest

import jointlab

SOURCE = pathlib.Path(os.environ.get("JOINTLAB_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
BINARY = pathlib.Path(os.environ.get("JOINTLAB_BINARY_DIR", SOURCE / "build"))
PROGRAM = BINARY / "bin" / "jointlab"
RECORD = SOURCE / "data" / "examples" / "brake-reuss-beam" / "hammer_impact.csv"


def run(*args):
    return subprocess.run([str(PROGRAM), *map(str, args)], capture_output=True, text=True)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, values = rows[0], np.array(rows[1:], dtype=float)
    return {name: values[:, k] for k, name in enumerate(header)}


def read_parameters(directory):
    """The command's parameters.csv in `directory`: its rows (dicts of text cells) by name."""
    with open(directory / "parameters.csv", newline="") as f:
        return {row["name"]: row for row in csv.DictReader(f)}


def assert_iwan_parameters_as_file(result, cli):
    """update_iwan's parameters agree with the command's parameters.csv row by row."""
    bound = {"lower": -1, "upper": 1, "": 0}
    for name, row in cli.items():
        p = result["parameters"][name]
        assert_close(p["final"], float(row["final"]))
        if name == "modal_ratio":  # the dict gives Z's absolute std, the file its relative
            std = None if p["std"] is None else p["std"] / p["final"]
        else:
            std = p["relative_std"]
        assert (std is None) == (row["relative_std"] == ""), name
        if std is not None:
            assert_close(std, float(row["relative_std"]))
        assert p["identifiable"] == (row["identifiable"] == "1"), name
        if name != "modal_ratio":
            assert p["held"] == (row["held"] == "1"), name
            assert p["at_bound"] == bound[row["at_bound"]], name
        assert p["note"] == row["note"], name


def assert_close(actual, expected, rel=1e-9):
    actual, expected = np.asarray(actual), np.asarray(expected)
    assert actual.shape == expected.shape
    np.testing.assert_allclose(actual, expected, rtol=rel, atol=0)


def two_mass_model(directory):
    """Two masses (1 kg each) on springs, an Iwan joint between mass 1 and ground."""
    d = pathlib.Path(directory)
    (d / "M.mtx").write_text(
        "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 1.0\n2 2 1.0\n")
    (d / "K.mtx").write_text(
        "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n"
        "1 1 2.0e5\n2 1 -1.0e5\n2 2 1.0e5\n")
    (d / "model.toml").write_text(
        '[matrices]\nmass = "M.mtx"\nstiffness = "K.mtx"\n\n'
        "[iwan.j]\nFs = 20.0\nKt = 5.0e4\nchi = -0.5\nbeta = 1.0\n\n"
        '[[joint]]\na = 0\nb = "ground"\nelement = "iwan.j"\n')
    return d / "model.toml"


def test_process_equals_the_command_line(tmp_path):
    out = tmp_path / "cli"
    r = run("process", RECORD, "--channel", "acc1", "--channel", "acc3", "--band", "70:90",
            "--out", out)
    assert r.returncode == 0, r.stderr
    backbones = jointlab.process([str(RECORD)], bands=[(70, 90)], channels=["acc1", "acc3"])
    assert [b.channel for b in backbones] == ["acc1", "acc3"]
    for b in backbones:
        assert b.band == 1
        csv_columns = read_csv(out / f"hammer_impact.{b.channel}.band1.csv")
        # vars(b): the column arrays alone, in the CSV's order (a table for pandas.DataFrame).
        assert list(vars(b)) == list(csv_columns)
        for name in ("time_s", "amplitude", "frequency_hz", "damping_ratio", "frequency_std_hz",
                     "damping_std", "harmonic", "exchange"):
            assert_close(getattr(b, name), csv_columns[name])
        assert not b.exchange.any()  # an ordinary record: no point exchanges energy
        assert 78 < b.linear_frequency_hz < 83  # the Brake-Reuss beam's first mode, ~80.5 Hz
        assert 0 < b.linear_damping_ratio < 0.05
    # The band's reference channel, as summary.json names it: one backbone per band.
    summary = json.loads((out / "summary.json").read_text())
    reference = summary["files"][0]["bands"][0]["reference_channel"]
    assert [b.channel for b in backbones if b.reference] == [reference]
    # Channels on one worker or several: the same numbers, bit for bit.
    one = jointlab.process([str(RECORD)], bands=[(70, 90)], channels=["acc1", "acc3"], threads=1)
    for a, b in zip(one, backbones):
        assert np.array_equal(a.frequency_hz, b.frequency_hz)
        assert np.array_equal(a.damping_ratio, b.damping_ratio)
        assert a.complex_amplitude == b.complex_amplitude


def test_process_options_and_out_as_the_command(tmp_path):
    # The command's --method, --snr-min, --max-damping-std, --coverage-factor and --min-share as
    # keywords, and `out` writing its folder: the same files, byte for byte (the folder that
    # update_linear's and update_iwan's `measured` read, made from Python alone).
    options = {"method": "pff", "snr_min": 50.0, "max_damping_std": 0.02, "coverage_factor": 2.0,
               "min_share": 0.2}
    r = run("process", RECORD, "--channel", "acc1", "--band", "70:90", "--method", "pff",
            "--snr-min", "50", "--max-damping-std", "0.02", "--coverage-factor", "2",
            "--min-share", "0.2", "--out", tmp_path / "cli")
    assert r.returncode == 0, r.stderr
    # Paths as pathlib.Path (any os.PathLike, as open() takes them; a TypeError before).
    (b,) = jointlab.process([RECORD], bands=[(70, 90)], channels=["acc1"],
                            out=tmp_path / "py" / "new", **options)
    names = sorted(f.name for f in (tmp_path / "cli").iterdir() if not f.name.startswith("."))
    assert names == ["hammer_impact.acc1.band1.csv", "summary.json"]
    for name in names:
        assert (tmp_path / "py" / "new" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    assert np.all(b.coverage_factor == 2.0)
    # The linear values' expanded uncertainties, as summary.json states them (12 digits).
    band = json.loads((tmp_path / "cli" / "summary.json").read_text())["files"][0]["bands"][0]
    assert_close(b.linear_frequency_std_hz, band["linear_frequency_std_hz"], 1e-11)
    assert_close(b.linear_damping_std, band["linear_damping_std"], 1e-11)
    # The amplitude's quantity and unit, the amplitudes the linear values were read over and the
    # noise floor, as summary.json (12 digits).
    assert (b.amplitude_quantity, b.amplitude_unit) == ("velocity", "m/s")
    assert_close(b.linear_fit_amplitude_min, band["linear_fit_amplitude_min"], 1e-11)
    assert_close(b.linear_fit_amplitude_max, band["linear_fit_amplitude_max"], 1e-11)
    output = json.loads((tmp_path / "cli" / "summary.json").read_text())["files"][0]["outputs"][0]
    assert_close(b.noise_floor_m, output["noise_floor_m"], 1e-11)
    for kwargs, message in (({"method": "fft"}, "--method fft: expected hilbert or pff"),
                            ({"coverage_factor": 11.0}, "--coverage-factor 11: must be in"),
                            ({"modes": 2}, "not both")):
        with pytest.raises(jointlab.InputError, match=message):
            jointlab.process([str(RECORD)], bands=[(70, 90)], **kwargs)


def test_qsma_and_modes_equal_the_command_line(tmp_path):
    model = two_mass_model(tmp_path)
    r = run("qsma", model, "--mode", "1", "--points", "30", "--out", tmp_path / "q.csv")
    assert r.returncode == 0, r.stderr
    expected = read_csv(tmp_path / "q.csv")
    curve = jointlab.Model(str(model)).qsma(mode=1, points=30)
    for name, values in expected.items():
        assert_close(curve[name], values)
    r = run("modes", model, "--out", tmp_path / "m.csv")
    assert r.returncode == 0, r.stderr
    with open(tmp_path / "m.csv", newline="") as f:
        rows = list(csv.DictReader(f))  # mode,frequency_hz,kind
    elastic = [float(r["frequency_hz"]) for r in rows if r["kind"] == "elastic"]
    assert_close(jointlab.Model(str(model)).modes(count=20), elastic)
    # The damping the command prints beside the table (the model has no [damping]: 0).
    assert "every elastic mode: 0 (the model has no [damping])" in r.stdout
    assert jointlab.Model(str(model)).modal_ratio == 0
    model.write_text(model.read_text() + "\n[damping]\nmodal_ratio = 0.002\n")
    assert jointlab.Model(model).modal_ratio == 0.002


def test_a_joint_with_chi_above_zero_is_read_as_by_the_command_line(tmp_path):
    # chi > -1 is the Iwan element's domain (method.md): chi 0.5 was refused ("chi = 0.5 must be
    # in (-1, 0]"); now the module reads it and its QSMA equals the command's, and chi -1 is
    # still refused naming the field.
    model = two_mass_model(tmp_path)
    model.write_text(model.read_text().replace("chi = -0.5", "chi = 0.5"))
    r = run("qsma", model, "--mode", "1", "--points", "10", "--out", tmp_path / "q.csv")
    assert r.returncode == 0, r.stderr
    curve = jointlab.Model(str(model)).qsma(mode=1, points=10)
    for name, values in read_csv(tmp_path / "q.csv").items():
        assert_close(curve[name], values)
    model.write_text(model.read_text().replace("chi = 0.5", "chi = -1.0"))
    with pytest.raises(jointlab.InputError, match=r"iwan.j: chi = -1 must be > -1"):
        jointlab.Model(str(model))


def test_shapes_are_the_mass_normalised_eigenvectors(tmp_path):
    # The two-mass Iwan model (K_lin = K + Kt at DOF 0, M = I) with dof_labels: the shapes
    # against numpy's eigh of the same matrices, to 1e-9 (the dense solve's rounding is ~1e-15
    # of the shapes' unit size), each column's sign as the solver's; phi^T M phi = I and the
    # residual K_lin phi - w^2 M phi to 1e-9 of K_lin's largest term.
    model = two_mass_model(tmp_path)
    (tmp_path / "dofs.csv").write_text("node,component\n7,3\n8,3\n")
    model.write_text(model.read_text().replace('stiffness = "K.mtx"\n',
                                               'stiffness = "K.mtx"\ndof_labels = "dofs.csv"\n'))
    m = jointlab.Model(model)
    assert m.dofs == 2 and m.dof_labels == ["7:3", "8:3"]
    assert repr(m) == f"<jointlab.Model {model}: 2 DOFs, 1 joint elements (1 Iwan)>"
    k = np.array([[2e5 + 5e4, -1e5], [-1e5, 1e5]])
    w2, expected = np.linalg.eigh(k)
    phi = m.shapes()
    assert phi.shape == (2, 2) and phi.dtype == np.float64
    assert_close(2 * np.pi * m.modes(), np.sqrt(w2))
    np.testing.assert_allclose(np.abs(phi), np.abs(expected), rtol=0, atol=1e-9)
    np.testing.assert_allclose(phi.T @ phi, np.eye(2), rtol=0, atol=1e-9)
    np.testing.assert_allclose(k @ phi - phi * w2, 0, rtol=0, atol=1e-9 * 2.5e5)
    assert m.shapes(count=1).shape == (2, 1)  # the columns of modes(count)
    (tmp_path / "plain").mkdir()
    assert jointlab.Model(two_mass_model(tmp_path / "plain")).dof_labels == []  # none named
    with pytest.raises(jointlab.InputError, match="^--count 0: must be >= 1$"):
        m.shapes(count=0)


def test_the_version_is_the_programs():
    r = run("--version")
    assert r.returncode == 0 and r.stdout.split() == ["jointlab", jointlab.__version__]


def test_read_record_gives_channels_in_si(tmp_path):
    rec = jointlab.read_record(str(RECORD))
    assert rec["sample_rate_hz"] > 0
    assert "acc1" in rec["channels"]
    data = rec["data"]["acc1"]
    assert isinstance(data, np.ndarray) and data.dtype == np.float64 and data.size > 1000
    # The samples' times, plot-ready: the file's time column to 2e-8 s, twice its 8 decimals'
    # rounding (5e-9 s) and the sample rate read from them (12799.99998750 Hz, 1e-9 relative:
    # 5e-9 s at 5.1 s); 1.0e-8 s at most here.
    rows = [line for line in RECORD.read_text().splitlines() if not line.startswith("#")]
    time = np.array([float(line.split(",")[0]) for line in rows[1:]])  # below the header
    assert rec["time_s"].shape == data.shape
    np.testing.assert_allclose(rec["time_s"], time, rtol=0, atol=2e-8)


def test_a_malformed_file_raises_a_value_error_naming_it(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("time,acc1 [g]\n0,1\nnot a number,2\n")
    with pytest.raises(ValueError, match="bad.csv"):
        jointlab.process([str(bad)], bands=[(70, 90)])
    r = run("process", bad, "--band", "70:90", "--out", tmp_path / "o")
    assert r.returncode == 2
    with pytest.raises(jointlab.InputError) as e:
        jointlab.process([str(bad)], bands=[(70, 90)])
    assert str(e.value) in r.stderr  # the command line's own line


def test_each_error_path_raises_input_error(tmp_path):
    with pytest.raises(jointlab.InputError, match="need 0 < LO < HI"):
        jointlab.process([str(RECORD)], bands=[(90, 70)])
    # The command's own words (it was "amplitude=speed: expected acceleration, ...").
    with pytest.raises(jointlab.InputError,
                       match="^--amplitude speed: expected displacement, velocity or acceleration$"):
        jointlab.process([str(RECORD)], bands=[(70, 90)], amplitude="speed")
    with pytest.raises(jointlab.InputError, match="^--quantity force: expected displacement"):
        jointlab.process([str(RECORD)], bands=[(70, 90)], quantity="force")
    # An empty list of channels is a mistake, not every channel (as it was: None is that).
    with pytest.raises(jointlab.InputError, match=r"channels=\[\] names no channel"):
        jointlab.process([RECORD], bands=[(70, 90)], channels=[])
    with pytest.raises(jointlab.InputError):
        jointlab.Model(str(tmp_path / "missing.toml"))
    model_file = two_mass_model(tmp_path)
    model = jointlab.Model(str(model_file))
    # A mode too large for a C++ integer is the command's message (a RuntimeError, "Unable to
    # cast Python instance", before), checked before any input is read.
    with pytest.raises(jointlab.InputError, match="^--mode 1000000000000000000000000000000: "):
        jointlab.update_iwan(model_file, "j", 10**30, ["none.csv"])
    with pytest.raises(jointlab.InputError, match="^--mode 1000000000000000000000000000000: "):
        jointlab.compare([model_file], 10**30, ["none.csv"])
    with pytest.raises(jointlab.InputError, match="--mode 0"):
        model.qsma(mode=0)
    with pytest.raises(jointlab.InputError, match="qmin and qmax"):
        model.qsma(mode=1, qmin=-1.0)
    # The command's range of --points (a million points was computed where the command refuses).
    with pytest.raises(jointlab.InputError, match=r"--points 100001: must be in \[2, 100000\]"):
        model.qsma(mode=1, points=100001)
    with pytest.raises(jointlab.InputError, match="--threads 2000"):
        jointlab.run(str(tmp_path / "campaign.toml"), str(tmp_path / "out"), threads=2000)


def test_an_integer_beyond_c_is_refused_naming_the_option_and_its_range(tmp_path):
    # An int argument given a Python int beyond C's int (threads=10**10) was pybind11's
    # TypeError, "incompatible function arguments" and the whole signature: now the command's
    # one-line message naming the option and its range, before any input is read. numpy
    # integers are still taken, the same numbers as Python's (bit for bit).
    model_file = two_mass_model(tmp_path)
    model = jointlab.Model(model_file)
    missing = tmp_path / "missing.csv"
    cases = [
        (lambda: jointlab.process(missing, bands=(70, 90), threads=10**10),
         r"--threads 10000000000: must be in \[0, 1024\] \(0: every core\)"),
        (lambda: jointlab.process(missing, modes=2**31), r"--modes 2147483648: must be in \[0, "),
        (lambda: jointlab.run(tmp_path / "c.toml", tmp_path / "o", threads=-10**12),
         r"--threads -1000000000000: must be in \[0, 1024\]"),
        (lambda: model.modes(count=10**30),
         r"--count 1000000000000000000000000000000: must be in \[1, 2147483647\]"),
        (lambda: model.shapes(count=-2**63 - 1), r"--count -9223372036854775809: must be in \[1, "),
        (lambda: model.qsma(mode=2**40), r"--mode 1099511627776: must be in \[1, 2147483647\]"),
        (lambda: model.qsma(mode=1, points=2**64), r"--points 18446744073709551616: must be in "
                                                   r"\[2, 100000\]"),
        (lambda: jointlab.compare([model_file], 1, [missing], points=10**20),
         r"--points 100000000000000000000: must be in \[2, 100000\]"),
        (lambda: jointlab.update_iwan(model_file, "j", 1, [missing], seed=2**70),
         r"--seed 1180591620717411303424: must be in \[0, 4294967295\]"),
        (lambda: jointlab.update_iwan(model_file, "j", 1, [missing], evaluations=2**40),
         r"--evaluations 1099511627776: must be in \[1, 2147483647\]"),
        (lambda: jointlab.update_iwan(model_file, "j", 1, [missing], threads=np.int64(2**40)),
         r"--threads 1099511627776: must be in \[0, 1024\]"),
        (lambda: jointlab.update_iwan(model_file, "j", 1, [missing], stepped_sine_mode=2**33),
         r"--stepped-sine-mode 8589934592: must be in \[0, 2147483647\]"),
    ]
    for call, message in cases:
        with pytest.raises(jointlab.InputError, match="^" + message):
            call()
    assert np.array_equal(model.modes(count=np.int64(2)), model.modes(count=2))
    assert np.array_equal(model.qsma(mode=np.int32(1), points=np.uint16(10))["frequency_hz"],
                          model.qsma(mode=1, points=10)["frequency_hz"])
    with pytest.raises(TypeError):  # a float is not an integer, as before
        model.modes(count=2.0)


def test_one_value_where_a_list_is_expected_is_a_list_of_one(tmp_path):
    # A str or a pathlib.Path for the files, a (lo, hi) pair for the bands, a str for the
    # channels, the sets or the holds: the command's repeatable option given once (each was
    # pybind11's "incompatible function arguments" TypeError, the whole signature in it). The
    # same computation, so the same numbers bit for bit.
    listed = jointlab.process([str(RECORD)], bands=[(70, 90)], channels=["acc1"])
    for one in (jointlab.process(RECORD, bands=(70, 90), channels="acc1"),
                jointlab.process(str(RECORD), bands=np.array([[70.0, 90.0]]),
                                 channels=("acc1",))):
        assert [(b.file, b.channel, b.band) for b in one] == [(str(RECORD), "acc1", 1)]
        assert np.array_equal(one[0].frequency_hz, listed[0].frequency_hz)
        assert np.array_equal(one[0].damping_ratio, listed[0].damping_ratio)
    table = two_mass_modes(tmp_path, 4e4)
    model = two_mass_spring_model(tmp_path, 1.2e5)
    sensors = tmp_path / "sensors.csv"
    a = jointlab.update_linear(model, ["spring.kj"], sensors, modes_table=table)
    b = jointlab.update_linear(model, "spring.kj", sensors, modes_table=table)
    assert a["parameters"]["spring.kj"]["final"] == b["parameters"]["spring.kj"]["final"]
    # None for a list not given, as process's channels=None (update_iwan's was a TypeError).
    c = jointlab.update_linear(model, "spring.kj", sensors, modes_table=table, hold=None)
    assert a["parameters"]["spring.kj"]["final"] == c["parameters"]["spring.kj"]["final"]
    with pytest.raises(jointlab.InputError, match="^--seed -1"):  # past the conversion
        jointlab.update_iwan(model, "j", 1, "none.csv", channels=None, stepped_sine=None,
                             pareto=None, seed=-1)
    held = jointlab.update_linear(model, "spring.kj", sensors, modes_table=table,
                                  hold="spring.kj=5e4")
    # Held at the value given: to 1e-12, its round trip through the fit's log coordinate.
    assert held["parameters"]["spring.kj"]["held_by_user"]
    assert_close(held["parameters"]["spring.kj"]["final"], 5e4, rel=1e-12)
    # bands=[] is no band, as None: modes=N alone (it was refused as "bands or modes=N, not both").
    with pytest.raises(jointlab.InputError, match="^give --band LO:HI or --modes N$"):
        jointlab.process(RECORD, bands=[])
    assert len(jointlab.process(RECORD, bands=[], modes=1, channels="acc1")) == 1
    # The command's words for a negative thread count or seed (pybind11's TypeError before), and
    # a progress that is not callable said before any work, naming the argument.
    with pytest.raises(jointlab.InputError, match=r"^--threads -1: must be in \[0, 1024\]"):
        jointlab.process(RECORD, bands=(70, 90), threads=-1)
    with pytest.raises(jointlab.InputError, match=r"^--threads -1: must be in \[0, 1024\]"):
        jointlab.run(tmp_path / "campaign.toml", tmp_path / "out", threads=-1)
    with pytest.raises(jointlab.InputError, match=r"^--seed -1: must be in \[0, 4294967295\]$"):
        jointlab.update_iwan(model, "j", 1, "none.csv", seed=-1)
    with pytest.raises(TypeError, match="^progress: expected a callable .* got int$"):
        jointlab.process(RECORD, bands=(70, 90), progress=5)
    # process()'s Backbones passed as backbones=: said with the way to pass them.
    bb = jointlab.process(RECORD, bands=(70, 90), channels="acc1")
    with pytest.raises(jointlab.InputError, match=r"^a jointlab.Backbone where a file is expected"
                                                  r": .* process\(\.\.\., out=DIR\)"):
        jointlab.update_iwan(model, "j", 1, bb)
    with pytest.raises(jointlab.InputError, match="^a jointlab.Backbone where a file"):
        jointlab.compare(model, 1, bb[0])
    # Modes as a numpy array are a list of modes, here two where tables need one
    # (np.array([1, 2]) was converted as one integer: a TypeError).
    with pytest.raises(jointlab.InputError, match="with --backbone give one --mode R"):
        jointlab.update_iwan(model, "j", np.array([1, 2]), "none.csv")


def test_a_backbone_pickles_with_its_arrays():
    # pickle, copy.deepcopy, joblib's cache and multiprocessing need it ("cannot pickle
    # 'jointlab.Backbone' object" before): every attribute back, the arrays bit for bit.
    import copy
    import pickle
    b = jointlab.process(RECORD, bands=(70, 90), channels="acc1")[0]
    for c in (pickle.loads(pickle.dumps(b)), copy.deepcopy(b)):
        assert type(c) is jointlab.Backbone and repr(c) == repr(b)
        for name in dir(b):
            if name.startswith("_"):
                continue
            a, z = getattr(b, name), getattr(c, name)
            if isinstance(a, np.ndarray):
                assert np.array_equal(a, z), name
            else:
                assert a == z, name


def test_progress_is_silent_unless_asked(capfd, tmp_path):
    # Around 1527 Hz acc2 sees the mode at 6.9 % of acc1's amplitude, below --min-share: no
    # Backbone, and why is the command's stderr line, here a progress line (it was lost).
    r = run("process", RECORD, "--band", "1480:1580", "--out", tmp_path / "cli")
    assert r.returncode == 0, r.stderr
    lines = []
    backbones = jointlab.process([str(RECORD)], bands=[(1480, 1580)], progress=lines.append)
    assert [b.channel for b in backbones] == ["acc1", "acc3"]
    assert lines == [f"process: {RECORD}"] + r.stderr.splitlines()
    assert "acc2 band 1: no backbone: sees this mode at 6.9 %" in lines[2]
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_fewer_modes_than_asked_are_returned_with_a_warning(tmp_path):
    # One mode (50 Hz, 0.5 % damping) read through a sensor with a 5 % square term, in noise:
    # modes=2 finds the mode, and the second peak (its harmonic at 100 Hz) gives no modal data.
    # The command writes the one mode and exits 2; here it is returned with a warning, and the
    # peak left out is a progress line, as the command's stderr has it.
    fs, n = 2048.0, 8192
    t = np.arange(n) / fs
    w = 2 * np.pi * 50.0
    x = np.exp(-0.005 * w * t) * np.sin(w * t)
    acc = x + 0.05 * x**2 + 1e-4 * np.random.default_rng(1).standard_normal(n)
    record = tmp_path / "one_mode.csv"
    np.savetxt(record, np.column_stack([t, acc]), delimiter=",", header="time,acc1 [m/s^2]",
               comments="")
    r = run("process", record, "--modes", "2", "--out", tmp_path / "cli")
    assert r.returncode == 2, r.stderr
    lines = []
    with pytest.warns(UserWarning, match="--modes 2: only 1 of the"):
        backbones = jointlab.process([str(record)], modes=2, progress=lines.append)
    assert len(backbones) == 1
    assert abs(backbones[0].linear_frequency_hz / 50.0 - 1) < 1e-3
    left_out = [line for line in lines if "is left out" in line]
    assert len(left_out) == 1 and "100.00 Hz" in left_out[0] and "superharmonic" in left_out[0]
    assert r.stderr.count("is left out") == 1
    # A band on the harmonic (90:110 Hz): a backbone every point of which is superharmonic, so
    # no linear values. The command writes none (summary.json's linear_reason) and exits 2;
    # here the values are None (they were 0 Hz and 0, and no warning) and a warning says why.
    r = run("process", record, "--band", "40:60", "--band", "90:110", "--out", tmp_path / "b")
    assert r.returncode == 2, r.stderr
    band = json.loads((tmp_path / "b" / "summary.json").read_text())["files"][0]["bands"][1]
    with pytest.warns(UserWarning, match="band 2 .90:110 Hz.: acc1: no linear values"):
        one, harmonic = jointlab.process([record], bands=[(40, 60), (90, 110)])
    assert harmonic.linear_reason == band["linear_reason"] and "linear_frequency_hz" not in band
    assert harmonic.linear_frequency_hz is None and harmonic.linear_damping_ratio is None
    assert harmonic.linear_frequency_std_hz is None and harmonic.linear_fit_amplitude_min is None
    assert "no linear values" in repr(harmonic) and harmonic.harmonic.all()
    assert one.linear_reason == "" and abs(one.linear_frequency_hz / 50.0 - 1) < 1e-3


def two_mass_spring_model(directory, kj):
    """Two 1 kg masses, each on a 1e5 N/m ground spring, joined by the joint spring.kj."""
    d = pathlib.Path(directory)
    (d / "M.mtx").write_text(
        "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 1.0\n2 2 1.0\n")
    (d / "K.mtx").write_text(
        "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 1.0e5\n2 2 2.0e5\n")
    (d / "model.toml").write_text(
        '[matrices]\nmass = "M.mtx"\nstiffness = "K.mtx"\n\n'
        f"[spring]\nkj = {kj!r}\n\n"
        '[[joint]]\na = 0\nb = 1\nelement = "spring.kj"\n')
    return d / "model.toml"


def two_mass_modes(directory, kj):
    """The two modes of two_mass_spring_model with kj as measured at both masses: writes
    modes.csv (returned) and sensors.csv (s0, s1 at DOFs 0 and 1) in directory."""
    d = pathlib.Path(directory)
    k = np.array([[1e5 + kj, -kj], [-kj, 2e5 + kj]])
    w2, phi = np.linalg.eigh(k)
    table = d / "modes.csv"
    table.write_text("mode,frequency_hz,s0,s1\n" + "".join(
        f"{i + 1},{np.sqrt(w2[i]) / (2 * np.pi)!r},{phi[0, i]!r},{phi[1, i]!r}\n"
        for i in range(2)))
    (d / "sensors.csv").write_text("channel,dof\ns0,0\ns1,1\n")
    return table


def test_update_linear_equals_the_command_line(tmp_path):
    # Measured: the two modes of the truth kj = 4e4 N/m with their shapes at both masses.
    truth = 4e4
    table = two_mass_modes(tmp_path, truth)
    model = two_mass_spring_model(tmp_path, 1.2e5)
    r = run("update-linear", model, "--modes-table", table, "--sensors", tmp_path / "sensors.csv",
            "--set", "spring.kj", "--out", tmp_path / "cli")
    assert r.returncode == 0, r.stderr
    cli = read_parameters(tmp_path / "cli")
    lines = []
    # `out` in a folder not yet made: made, as the command makes its --out (it was refused after
    # the fit, naming a temporary file).
    result = jointlab.update_linear(str(model), ["spring.kj"], str(tmp_path / "sensors.csv"),
                                    modes_table=str(table), progress=lines.append,
                                    out=str(tmp_path / "py" / "new" / "model.toml"))
    p = result["parameters"]["spring.kj"]
    assert_close(p["final"], float(cli["spring.kj"]["final"]))
    assert p["one_sided"] == 0 and p["smallest_within_tolerance"] is None  # an empty cell
    assert (tmp_path / "py" / "new" / "model.toml").read_text() == \
        (tmp_path / "cli" / "model.toml").read_text()
    assert abs(p["final"] / truth - 1) < 1e-6  # noise-free data: the truth
    assert result["converged"]
    assert result["starts"] == 1 and result["restarts"] == ""  # a fit within the noise: no restart
    assert [m["model_mode"] for m in result["modes"]] == [1, 2]
    # The MAC matrix at the result, as mac.csv (measured rows, model columns from 1).
    with open(tmp_path / "cli" / "mac.csv", newline="") as f:
        mac = [row[1:] for row in csv.reader(f)][1:]
    assert result["mac"].dtype == np.float64
    assert_close(result["mac"], np.array(mac, dtype=float))
    assert lines and lines[0].startswith("update-linear: iteration")
    # history.csv and sweeps.csv as arrays (the command's only, before): the same numbers to the
    # files' 10 digits, an empty cell as NaN.
    history = read_csv(tmp_path / "cli" / "history.csv")
    assert list(result["history"]) == list(history)
    for name, values in history.items():
        assert_close(result["history"][name], values)
    with open(tmp_path / "cli" / "sweeps.csv", newline="") as f:
        rows = list(csv.reader(f))
    sweeps = np.array([[float(c) if c else np.nan for c in row[1:]] for row in rows[1:]])
    sweep = p["sweep"]
    assert_close(sweep["factor"], sweeps[:, 0])
    assert_close(sweep["stiffness"], sweeps[:, 1])
    assert_close(sweep["rms_error"], sweeps[:, 2])
    assert_close(sweep["errors"], sweeps[:, 3:])
    assert sweep["errors"].shape == (9, 2)  # 9 points, both measured modes
    assert p["lower"] == 1.2e5 * 1e-3 and p["upper"] == 1.2e5 * 1e3  # the default factors
    # Each mode keeps the table's own number, as modes.csv writes it.
    numbered = tmp_path / "numbered.csv"
    numbered.write_text(table.read_text().replace("\n1,", "\n3,").replace("\n2,", "\n5,"))
    result = jointlab.update_linear(str(model), ["spring.kj"], str(tmp_path / "sensors.csv"),
                                    modes_table=str(numbered))
    assert [m["measured"] for m in result["modes"]] == [3, 5]
    # --bound and --alias-mac as bounds= and alias_mac=: the truth 4e4 N/m lies below the bound,
    # so both stop at it (1e5), the same to 10 digits.
    r = run("update-linear", model, "--modes-table", table, "--sensors", tmp_path / "sensors.csv",
            "--set", "spring.kj", "--bound", "spring.kj=1e5:2e5", "--alias-mac", "0.95",
            "--out", tmp_path / "cli_bound")
    assert r.returncode == 0, r.stderr
    cli = read_parameters(tmp_path / "cli_bound")
    bounded = jointlab.update_linear(str(model), ["spring.kj"], str(tmp_path / "sensors.csv"),
                                     modes_table=str(table), bounds={"spring.kj": (1e5, 2e5)},
                                     alias_mac=0.95)
    assert_close(bounded["parameters"]["spring.kj"]["final"], float(cli["spring.kj"]["final"]))
    assert bounded["parameters"]["spring.kj"]["at_bound"] == -1
    assert bounded["report"] == r.stdout
    # Two pairs for one set leave one degree of freedom; one pair none, and no reduced
    # chi-square (it was 0.0, a perfect fit's, where the report warns that nothing checks it).
    assert result["degrees_of_freedom"] == 1 and result["reduced_chi2"] > 0
    single = tmp_path / "single.csv"
    single.write_text("".join(table.read_text().splitlines(keepends=True)[:2]))
    one = jointlab.update_linear(str(model), ["spring.kj"], str(tmp_path / "sensors.csv"),
                                 modes_table=str(single))
    assert one["degrees_of_freedom"] == 0 and one["reduced_chi2"] is None
    assert "no degree of freedom is left" in one["report"]
    # The paper's rule: the smallest stiffness within 1 %, parameters.csv's column.
    r = run("update-linear", model, "--modes-table", table, "--sensors", tmp_path / "sensors.csv",
            "--set", "spring.kj", "--rule", "smallest", "--minimize", "spring.kj",
            "--out", tmp_path / "cli_smallest")
    assert r.returncode == 0, r.stderr
    cli = read_parameters(tmp_path / "cli_smallest")
    smallest = jointlab.update_linear(str(model), ["spring.kj"], str(tmp_path / "sensors.csv"),
                                      modes_table=str(table), rule="smallest",
                                      minimize="spring.kj")
    assert_close(smallest["parameters"]["spring.kj"]["smallest_within_tolerance"],
                 float(cli["spring.kj"]["smallest_within_tolerance"]))
    # The command's refusals of its options: a value not read whole, no set.
    for kwargs, message in (({"hold": ["spring.kj=1e5xyz"]}, "1e5xyz is not a finite number"),
                            ({"bounds": {"spring.kj": (2e5, 1e5)}}, "need 0 < LO < HI"),
                            ({"bound_factors": (0.5, 0.9)}, "need 0 < LO < 1 < HI")):
        with pytest.raises(jointlab.InputError, match=message):
            jointlab.update_linear(str(model), ["spring.kj"], str(tmp_path / "sensors.csv"),
                                   modes_table=str(table), **kwargs)
    with pytest.raises(jointlab.InputError, match="give at least one set"):
        jointlab.update_linear(str(model), [], str(tmp_path / "sensors.csv"),
                               modes_table=str(table))
    # A shape that is zero at every sensor is refused as by the command.
    table.write_text("mode,frequency_hz,s0,s1\n1,50.0,0,0\n2,80.0,1,1\n")
    with pytest.raises(jointlab.InputError, match="zero at every sensor"):
        jointlab.update_linear(str(model), ["spring.kj"], str(tmp_path / "sensors.csv"),
                               modes_table=str(table))


def test_update_linear_states_the_spread_and_the_sigmas_of_its_report(tmp_path):
    # A process folder of three hits of the two-mass truth (kj = 4e4 N/m): mode 1 read at
    # 1, 1.005 and 0.995 times its frequency (stated to 1e-5, no trend with level), mode 2 the
    # same in each. The report's WARNING on band 1 and its profile sigma (with the local slope's,
    # which it says understates it) are fields of the result, as the report prints them.
    truth = 4e4
    model = two_mass_spring_model(tmp_path, 1.2e5)
    w2, phi = np.linalg.eigh(np.array([[1e5 + truth, -truth], [-truth, 2e5 + truth]]))
    f = np.sqrt(w2) / (2 * np.pi)
    (tmp_path / "sensors.csv").write_text("channel,dof\ns0,0\ns1,1\n")
    files = []
    for hit, (scale, level) in enumerate(((1.0, 1e-3), (1.005, 1.1e-3), (0.995, 1.2e-3))):
        bands = []
        for i in range(2):
            fi = f[i] * (scale if i == 0 else 1.0)
            bands.append({
                "band": i + 1, "low_hz": 0.8 * fi, "high_hz": 1.2 * fi,
                "reference_channel": "s0", "linear_frequency_hz": fi,
                "linear_frequency_std_hz": 1e-5 * fi, "linear_damping_ratio": 1e-3,
                "linear_damping_std": 1e-5, "linear_fit_amplitude_min": level,
                "operating_shape": [{"channel": f"s{k}", "real_m": phi[k, i], "imag_m": 0}
                                    for k in range(2)]})
        files.append({"file": f"hit{hit}.csv", "bands": bands, "outputs": []})
    (tmp_path / "p").mkdir()
    (tmp_path / "p" / "summary.json").write_text(json.dumps({
        "program": "jointlab process", "method": "hilbert", "amplitude_quantity": "velocity",
        "amplitude_unit": "m/s", "coverage_factor": 3, "files": files}))
    r = run("update-linear", model, "--measured", tmp_path / "p", "--sensors",
            tmp_path / "sensors.csv", "--set", "spring.kj", "--out", tmp_path / "cli")
    assert r.returncode == 0, r.stderr
    result = jointlab.update_linear(model, ["spring.kj"], tmp_path / "sensors.csv",
                                    measured=tmp_path / "p")
    assert result["report"] == r.stdout
    assert any(w.startswith("band 1: the 3 files' linear frequencies") for w in result["warnings"])
    # Band 1's files spread by a standard deviation of 0.5 % of their mean (n - 1: 0.005 to
    # rounding, 1e-9); band 2's agree, no spread stated.
    spread = [m["frequency_spread_std"] for m in result["modes"]]
    assert_close(spread[0], 0.005)
    assert spread[1] is None
    p = result["parameters"]["spring.kj"]
    assert p["held_by_user"] is False and result["sigma_from_scatter"] is False
    # The sigma and the local slope's, three digits each as the report prints them.
    assert p["slope_std"] is not None and p["slope_std"] < p["relative_std"]
    assert (f"+/- {100 * p['relative_std']:.3g} % (a third of where the chi-square's profile "
            f"rises by 9; the local slope's {100 * p['slope_std']:.3g} % understates it)"
            ) in result["report"]
    cli = read_parameters(tmp_path / "cli")
    assert_close(p["relative_std"], float(cli["spring.kj"]["relative_std"]))


def test_update_linear_names_sets_acting_together(tmp_path):
    # Two springs between the same two masses (spring.kj beside spring.kd): every frequency sees
    # only their sum, so neither is identifiable alone and the sum is the combination determined,
    # as parameters.csv (identifiable 0) and the report's warning say.
    truth = 4e4
    table = two_mass_modes(tmp_path, truth)
    # From a sum near the truth's (from kj 1.2e5 the fit drives kd to its lower bound, where it
    # is flat and held at its start; the two are named as acting together all the same,
    # LinearUpdate.ASetHeldFlatAfterTheFitDroveItAwayStillActsTogether).
    model = two_mass_spring_model(tmp_path, 2.0e4)
    model.write_text(model.read_text().replace("[spring]\n", "[spring]\nkd = 3.0e4\n")
                     + '\n[[joint]]\na = 0\nb = 1\nelement = "spring.kd"\n')
    sets = ["spring.kj", "spring.kd"]
    r = run("update-linear", model, "--modes-table", table, "--sensors", tmp_path / "sensors.csv",
            "--set", sets[0], "--set", sets[1], "--out", tmp_path / "cli")
    assert r.returncode == 0, r.stderr
    cli = read_parameters(tmp_path / "cli")
    result = jointlab.update_linear(str(model), sets, str(tmp_path / "sensors.csv"),
                                    modes_table=str(table))
    for name, other in zip(sets, reversed(sets)):
        p = result["parameters"][name]
        assert p["identifiable"] is False and cli[name]["identifiable"] == "0"
        assert p["acts_with"] == [other]
        assert p["relative_std"] is None
    [c] = result["collinear"]
    assert c["sets"] == sets and c["determined"] == 1 and c["correlation"] > 0.999
    assert c["weight"] == pytest.approx(1.0, rel=1e-9)
    assert c["value"] == pytest.approx(truth, rel=1e-6)  # the sum, noise-free: the truth
    assert c["relative_std"] is None or c["relative_std"] > 0
    assert "act together" in " ".join(result["warnings"])
    # One set alone is identifiable and nothing acts together.
    result = jointlab.update_linear(str(model), ["spring.kj"], str(tmp_path / "sensors.csv"),
                                    modes_table=str(table))
    assert result["parameters"]["spring.kj"]["identifiable"] is True
    assert result["collinear"] == []


def twin_chains_model(directory, kg, kc):
    """Two chains of three masses (1 and 1.05 kg, inner springs 1e4 N/m), each grounded by
    spring.kg and coupled at their tips by spring.kc; returns the model file, M and K."""
    d = pathlib.Path(directory)
    mass = np.array([1.0, 1.0, 1.0, 1.05, 1.05, 1.05])
    k = np.zeros((6, 6))
    for a in (0, 1, 3, 4):
        k[a:a + 2, a:a + 2] += 1e4 * np.array([[1.0, -1.0], [-1.0, 1.0]])
    (d / "M.mtx").write_text("%%MatrixMarket matrix coordinate real symmetric\n6 6 6\n" + "".join(
        f"{i + 1} {i + 1} {mass[i]!r}\n" for i in range(6)))
    cells = [(i, j, k[i, j]) for i in range(6) for j in range(i + 1) if k[i, j] != 0]
    (d / "K.mtx").write_text(
        f"%%MatrixMarket matrix coordinate real symmetric\n6 6 {len(cells)}\n"
        + "".join(f"{i + 1} {j + 1} {v!r}\n" for i, j, v in cells))
    (d / "model.toml").write_text(
        '[matrices]\nmass = "M.mtx"\nstiffness = "K.mtx"\n\n'
        f"[spring]\nkg = {kg!r}\nkc = {kc!r}\n\n"
        '[[joint]]\na = 0\nb = "ground"\nelement = "spring.kg"\n\n'
        '[[joint]]\na = 3\nb = "ground"\nelement = "spring.kg"\n\n'
        '[[joint]]\na = 2\nb = 5\nelement = "spring.kc"\n')
    k[0, 0] += kg
    k[3, 3] += kg
    k[2:6:3, 2:6:3] += kc * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return d / "model.toml", np.diag(mass), k


def test_update_linear_pairs_the_shapes_do_not_confirm_are_not_converged(tmp_path):
    # The twin chains (docs/update-linear.md): six modes of the truth kg 1e4, kc 500 measured at
    # the two tips with channel a reversed, fitted from kg 8e3, kc 800: modes 1 and 2 pair
    # crosswise and the shapes no longer confirm them at the result. The fit converged, but the
    # result is not called converged, as the command's headline says.
    _, m, k = twin_chains_model(tmp_path, 1e4, 500.0)
    w2, phi = np.linalg.eigh(np.linalg.solve(np.sqrt(m), np.linalg.solve(np.sqrt(m), k).T))
    phi = np.linalg.solve(np.sqrt(m), phi)
    table = tmp_path / "modes.csv"
    table.write_text("mode,frequency_hz,a,b\n" + "".join(
        f"{i + 1},{np.sqrt(w2[i]) / (2 * np.pi)!r},{-phi[2, i]!r},{phi[5, i]!r}\n"
        for i in range(6)))
    (tmp_path / "sensors.csv").write_text("channel,dof\na,2\nb,5\n")
    model, _, _ = twin_chains_model(tmp_path, 8e3, 800.0)
    sets = ["spring.kg", "spring.kc"]
    result = jointlab.update_linear(str(model), sets, str(tmp_path / "sensors.csv"),
                                    modes_table=str(table))
    assert result["status"] == "pairs_unconfirmed"
    assert result["converged"] is False
    assert result["unconfirmed_modes"] == [1, 2]
    assert result["unconfirmed"].startswith(
        "the shapes do not confirm the pairs of test modes 1 and 2")
    assert "pairs unconfirmed by the shapes (the fit converged)" in result["report"]
    assert [m["model_mode"] for m in result["modes"]][:2] == [2, 1]  # crosswise
    # Given at sensor b alone, modes 1 and 2 pair by frequency: converged at the truth.
    rows = table.read_text().splitlines()
    for i in (1, 2):
        cells = rows[i].split(",")
        rows[i] = ",".join(cells[:2] + [""] + cells[3:])
    table.write_text("\n".join(rows) + "\n")
    result = jointlab.update_linear(str(model), sets, str(tmp_path / "sensors.csv"),
                                    modes_table=str(table))
    assert result["status"] == "converged" and result["converged"] is True
    assert result["unconfirmed"] == "" and result["unconfirmed_modes"] == []
    assert result["parameters"]["spring.kg"]["final"] == pytest.approx(1e4, rel=1e-5)
    assert result["parameters"]["spring.kc"]["final"] == pytest.approx(500, rel=1e-5)


@pytest.fixture(scope="module")
def riveted_model(tmp_path_factory):
    # The example riveted beam's model, built once for the tests that need it (about 3 s).
    directory = tmp_path_factory.mktemp("riveted")
    r = run("build-model", SOURCE / "examples" / "riveted_beam" / "description.toml", "--out",
            directory / "model", "--quiet")
    assert r.returncode == 0, r.stderr
    return directory / "model" / "model.toml"


def test_run_equals_the_command_line(tmp_path, riveted_model):
    # The example campaign (nine hits): the scatter summaries and the updated model file of both
    # runs are the same files, byte for byte. Its model is built once for both (built in each
    # run, it was 9 s of each run's 20 s) and the Iwan step given 100 evaluations, not 400.
    example = SOURCE / "data" / "examples" / "riveted-campaign"
    text = (example / "campaign.toml").read_text()
    for old, new in (
            ('description = "../../../examples/riveted_beam/description.toml"',
             f'file = "{riveted_model}"'),
            ('truth = "truth.toml"', f'truth = "{example / "truth.toml"}"'),
            ('"low/', f'"{example}/low/'), ('"mid/', f'"{example}/mid/'),
            ('"high/', f'"{example}/high/'),
            ("max_evaluations = 400", "max_evaluations = 100")):
        assert old in text, old
        text = text.replace(old, new)
    campaign = tmp_path / "campaign.toml"
    campaign.write_text(text)
    r = run("run", campaign, "--out", tmp_path / "cli", "--quiet")
    assert r.returncode == 0, r.stderr
    lines = []
    s = jointlab.run(str(campaign), str(tmp_path / "py"), progress=lines.append)
    assert s["hits"] == 9 and s["failed_hits"] == [] and s["no_backbone"] == []
    assert s["refused"] == [] and s["stopped"] == []  # its linear pairs are confirmed
    # A model file given, not a description: neither built nor reused, as the report says.
    assert s["model_built"] is False and s["model_reused"] is False
    assert "model" not in s["report"].splitlines()[0]
    assert pathlib.Path(s["report_html"]).exists()
    assert len(lines) > 5
    for name in ("scatter/mode1.bins.csv", "scatter/mode2.bins.csv", "qsma/mode1.updated.csv"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    with pytest.raises(jointlab.InputError, match="missing.toml"):
        jointlab.run(str(tmp_path / "missing.toml"), str(tmp_path / "none"))


def test_update_iwan_from_a_process_folder_equals_the_command_line(tmp_path, riveted_model):
    # The example campaign's mid and high hits processed in two bands, the riveted beam's model at
    # its start and the campaign's two sensors: `measured=` reads the folder as `--measured`
    # does, so the call and the command end at the same parameters, with the same report.
    example = SOURCE / "data" / "examples" / "riveted-campaign"
    hits = sorted((example / "mid").glob("*.csv")) + sorted((example / "high").glob("*.csv"))
    r = run("process", *hits, "--band", "100:145", "--band", "440:570", "--out", tmp_path / "p")
    assert r.returncode == 0, r.stderr
    (tmp_path / "sensors.csv").write_text("channel,dof\nacc_9001_z,9001:3\nacc_9003_z,9003:3\n")
    r = run("update-iwan", riveted_model, "--set", "rivet", "--mode", "1", "--measured",
            tmp_path / "p", "--sensors", tmp_path / "sensors.csv", "--evaluations", "100",
            "--out", tmp_path / "cli")
    assert r.returncode == 0, r.stderr
    cli = read_parameters(tmp_path / "cli")
    result = jointlab.update_iwan(str(riveted_model), "rivet", 1, measured=str(tmp_path / "p"),
                                  sensors=str(tmp_path / "sensors.csv"), evaluations=100)
    assert_iwan_parameters_as_file(result, cli)
    # The command prints the slip screen (band 2's mode screens mode 1's points, as `run`'s other
    # [[mode]]s do) before its report; the call gives it to progress, the report alike.
    assert r.stdout.startswith("slip screen"), r.stdout
    assert r.stdout.endswith(result["report"]) and result["report"].startswith("Iwan update:")
    # Two modes as the command's repeated --mode (R and R:BAND): the slip screen is a progress
    # line, as the command prints it. Ctrl-C during the fit ends it (the 100 evaluations, 4 s,
    # ran to the end, the model written, and only then KeyboardInterrupt): sent from another
    # thread once the slip screen's line is out, so that it lands while the fit runs.
    lines = []
    screened = threading.Event()
    sender = threading.Thread(
        target=lambda: screened.wait(60) and lines and os.kill(os.getpid(), signal.SIGINT))

    def progress(line):
        lines.append(line)
        screened.set()

    handler = signal.signal(signal.SIGINT, signal.default_int_handler)
    sender.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            jointlab.update_iwan(riveted_model, "rivet", [1, "3:2"], measured=tmp_path / "p",
                                 sensors=tmp_path / "sensors.csv", evaluations=100,
                                 progress=progress, out=tmp_path / "stopped" / "model.toml")
    finally:
        screened.set()
        sender.join()
        signal.signal(signal.SIGINT, handler)
    assert any(line.startswith("slip screen") for line in lines), lines
    assert not (tmp_path / "stopped" / "model.toml").exists()
    # The command's argument errors, raised the same way.
    with pytest.raises(jointlab.InputError, match="--amplitude and --dof describe --backbone"):
        jointlab.update_iwan(str(riveted_model), "rivet", 1, measured=str(tmp_path / "p"),
                             sensors=str(tmp_path / "sensors.csv"), amplitude="velocity")
    with pytest.raises(jointlab.InputError, match="give --measured DIR with --sensors FILE"):
        jointlab.update_iwan(str(riveted_model), "rivet", 1, measured=str(tmp_path / "p"))
    with pytest.raises(jointlab.InputError, match="--mode 1:9: .* has no band 9"):
        jointlab.update_iwan(str(riveted_model), "rivet", "1:9", measured=str(tmp_path / "p"),
                             sensors=str(tmp_path / "sensors.csv"))


def one_mode_iwan(d, points):
    # A one-mode model (unit mass, 3.3e5 N/m, an Iwan joint to ground) as truth.toml (Fs 30 N,
    # Kt 1.4e4 N/m, chi -0.5) and start.toml (60, 1.2e4, -0.3), and the truth's own ring-down
    # QSMA columns at `points` modal amplitudes as the backbone table bb.csv; returns the columns.
    (d / "M.mtx").write_text("%%MatrixMarket matrix coordinate real symmetric\n1 1 1\n1 1 1.0\n")
    (d / "K.mtx").write_text("%%MatrixMarket matrix coordinate real symmetric\n1 1 1\n1 1 3.3e5\n")
    body = ('[matrices]\nmass = "M.mtx"\nstiffness = "K.mtx"\n\n'
            "[iwan.j]\nFs = {fs}\nKt = {kt}\nchi = {chi}\nbeta = 1.5\n\n"
            '[[joint]]\na = 0\nb = "ground"\nelement = "iwan.j"\n')
    (d / "truth.toml").write_text(body.format(fs=30.0, kt=1.4e4, chi=-0.5))
    (d / "start.toml").write_text(body.format(fs=60.0, kt=1.2e4, chi=-0.3))
    r = run("qsma", d / "truth.toml", "--mode", "1", "--points", str(points), "--qmin", "1e-5",
            "--qmax", "1e-3", "--out", d / "q.csv")
    assert r.returncode == 0, r.stderr
    q = read_csv(d / "q.csv")
    with open(d / "bb.csv", "w") as f:
        f.write("amplitude,frequency_hz,damping_ratio\n")
        for a, fr, z in zip(q["modal_amplitude"], q["ringdown_frequency_hz"],
                            q["ringdown_damping_ratio"]):
            f.write(f"{a!r},{fr!r},{z!r}\n")
    return q


def test_update_iwan_names_the_set_that_carries_the_mode_as_the_command(tmp_path):
    # The one-mode truth's table fitted with a second Iwan set beside the joint (as stiff as
    # the truth's, slipping at 100 times the force: next to no dissipation in the model as given)
    # as the set to update: the command and the call both say that the other set carries the
    # mode's joint dissipation, in the report and (the call) in its warnings.
    d = tmp_path
    one_mode_iwan(d, points=20)
    # The joint beside it softer than the truth's (Kt 1e4 N/m), so that the data lie within what
    # the updated set reaches with it.
    body = (d / "truth.toml").read_text().replace("Kt = 14000.0", "Kt = 10000.0")
    assert "Kt = 10000.0" in body
    (d / "two.toml").write_text(
        body + "\n[iwan.k]\nFs = 3000.0\nKt = 1.4e4\nchi = -0.5\nbeta = 1.0\n\n"
        '[[joint]]\na = 0\nb = "ground"\nelement = "iwan.k"\n')
    r = run("update-iwan", d / "two.toml", "--set", "k", "--mode", "1", "--backbone",
            d / "bb.csv", "--evaluations", "100", "--out", d / "cli")
    assert r.returncode == 0, r.stderr
    result = jointlab.update_iwan(d / "two.toml", "k", 1, [d / "bb.csv"], evaluations=100)
    assert result["report"] == r.stdout
    shares = [w for w in result["warnings"] if "iwan.j" in w and "carries" in w]
    assert len(shares) == 1, result["warnings"]
    assert shares[0] in r.stdout


def test_compare_gives_the_curves_the_command_draws(tmp_path):
    # The one-mode model's own ring-down QSMA columns as a table, against the truth and the start:
    # the curves equal the CSV `jointlab compare` writes beside its figure (10 digits), the truth's
    # lies on the table, and `out` draws the same figure and CSV.
    d = tmp_path
    q = one_mode_iwan(d, points=30)
    models = [str(d / "truth.toml"), str(d / "start.toml")]
    r = run("compare", *models, "--backbone", d / "bb.csv", "--mode", "1", "--points", "20",
            "--label", "truth", "--label", "start", "--out", d / "cli.png")
    assert r.returncode == 0, r.stderr
    c = jointlab.compare(models, 1, [str(d / "bb.csv")], labels=["truth", "start"], points=20,
                         out=str(d / "py.png"))
    assert [m["label"] for m in c["models"]] == ["truth", "start"]
    assert not any(m["clipped"] for m in c["models"])
    with open(d / "cli.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    for m in c["models"]:
        mine = [row for row in rows if row["model"] == m["label"]]
        assert len(mine) == len(m["amplitude"]) == 20
        for row, a, fr, z in zip(mine, m["amplitude"], m["frequency_hz"], m["damping_ratio"]):
            assert_close(a, float(row["amplitude"]))
            assert_close(fr, float(row["frequency_hz"]))
            assert_close(z, float(row["damping_ratio"]))
    assert (d / "py.csv").read_bytes() == (d / "cli.csv").read_bytes()
    assert (d / "py.png").stat().st_size > 0
    # The truth's curve is the table it was made from: read between its 20 points by straight
    # lines, within 1e-4 (the frequency changes by about 1 % between neighbouring points).
    truth = c["models"][0]
    np.testing.assert_allclose(np.interp(q["modal_amplitude"], truth["amplitude"],
                                         truth["frequency_hz"]),
                               q["ringdown_frequency_hz"], rtol=1e-4)
    assert c["measured"][0]["source"].endswith("bb.csv")
    with pytest.raises(jointlab.InputError, match="--label for 2 models"):
        jointlab.compare(models, 1, [str(d / "bb.csv")], labels=["one"])
    # A figure folder that cannot be made (under a file): the user's mistake, not a RuntimeError.
    with pytest.raises(jointlab.InputError, match="cannot create the output directory"):
        jointlab.compare(models, 1, [str(d / "bb.csv")], out=str(d / "bb.csv" / "c.png"))


def test_update_iwan_says_when_the_sigmas_rest_on_scatter_between_hits(tmp_path):
    # Three hits of the one-mode truth whose joints differ (its table read at amplitudes 0.85,
    # 1 and 1.15 times, as F_S scattered 15 % between the hits), 1e-4 and 2 % noise stated and
    # drawn: the curves disagree beyond their noise, the report names the scatter and its sigmas
    # rest on it (one cluster per hit), and the result says so as the report does. One curve:
    # nothing to say (None).
    d = tmp_path
    q = one_mode_iwan(d, points=30)
    rng = np.random.default_rng(1)
    files = []
    for h, scale in enumerate((0.85, 1.0, 1.15)):
        files.append(d / f"hit{h}.csv")
        with open(files[-1], "w") as f:
            f.write("amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std\n")
            for a, fr, z in zip(q["modal_amplitude"], q["ringdown_frequency_hz"],
                                q["ringdown_damping_ratio"]):
                f.write(f"{a * scale!r},{fr * (1 + 1e-4 * rng.standard_normal())!r},"
                        f"{z * (1 + 0.02 * rng.standard_normal())!r},{fr * 1e-4!r},{z * 0.02!r}\n")
    result = jointlab.update_iwan(d / "start.toml", "iwan.j", 1, files, evaluations=400)
    scatter = result["scatter_between_hits"]
    assert result["misfit"] and scatter is not None
    assert scatter["curves"] == 3 and scatter["apart"] is None
    assert 0 < scatter["offsets_share"] <= 1 and 0 <= scatter["shapes_share"] <= 1
    assert scatter["sigmas_from_scatter"]
    assert "the sigmas allow for it (one cluster per hit" in result["report"]
    assert result["parameters"]["Kt"]["relative_std"] is not None
    one = jointlab.update_iwan(d / "start.toml", "iwan.j", 1, [d / "bb.csv"], evaluations=400)
    assert one["scatter_between_hits"] is None


def test_update_iwan_equals_the_command_line(tmp_path, capfd):
    # A one-mode model (unit mass, 3.3e5 N/m, an Iwan joint to ground) and its own ring-down
    # QSMA columns as a backbone table: the command and the call end at the same parameters.
    d = tmp_path
    q = one_mode_iwan(d, points=40)
    r = run("update-iwan", d / "start.toml", "--set", "iwan.j", "--mode", "1", "--backbone",
            d / "bb.csv", "--evaluations", "400", "--out", d / "cli")
    assert r.returncode == 0, r.stderr
    cli = read_parameters(d / "cli")
    lines = []
    result = jointlab.update_iwan(str(d / "start.toml"), "iwan.j", 1, [str(d / "bb.csv")],
                                  evaluations=400, progress=lines.append)
    assert_iwan_parameters_as_file(result, cli)
    # The search's history as arrays, as history.csv (stage "beta held" / "beta free").
    with open(d / "cli" / "history.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    h = result["history"]
    assert h["beta_held"].dtype == np.bool_
    assert_close(h["evaluation"], [float(row["evaluation"]) for row in rows])
    assert_close(h["objective"], [float(row["objective"]) for row in rows])
    assert_close(h["best"], [float(row["best"]) for row in rows])
    assert list(h["beta_held"]) == [row["stage"] == "beta held" for row in rows]
    # A progress line at the first evaluation at or past 250: the local solve's count steps over
    # 250 itself here (423 evaluations, and no line at all, as the command prints none).
    assert len(lines) == 1, lines
    words = lines[0].split()
    assert words[0] == "update-iwan:" and words[2:6] == ["QSMA", "evaluations,", "best", "cost"]
    assert 250 <= int(words[1]) <= result["evaluations"]
    # Converged, as the report says; a fit that is not states no sigma.
    assert result["converged"]
    assert not result["no_slip"]
    assert result["report"].startswith("Iwan update: converged")
    # The fit's statistics behind the sigmas, as the report prints them.
    assert f"reduced chi-square {result['reduced_chi2']:.3g}" in result["report"]
    n_fitted = sum(1 for k in ("Fs", "Kt", "chi", "beta") if result["parameters"][k]["fitted"])
    assert_close(result["sigma_degrees_of_freedom"], result["effective_points"] - n_fitted)
    assert 0 <= result["noise_correlation"] < 1
    # A sigma is stated exactly where its Student's t has a variance (more than 2 degrees).
    stated = result["parameters"]["Kt"]["relative_std"] is not None
    assert stated == (result["sigma_degrees_of_freedom"] > 2)
    # The linear part's systematic effect as the report's "linear part:" line states it: the
    # change per 0.1 % error of mode 1's linear frequency (two digits), stated for Kt here.
    rates = {k: result["parameters"][k]["linear_part_sensitivity"] for k in ("Fs", "Kt", "chi")}
    assert rates["Kt"] is not None
    for name, rate in rates.items():
        if rate is not None and abs(0.1 * rate) >= 1e-3:  # smaller: "by less than 0.001 %"
            assert f"{name} by {0.1 * rate:+.2g} %" in result["report"], (name, rate)
    # The report says what the amplitudes were read as, as the command's does.
    assert "amplitudes read as mode 1's QSMA modal amplitude q (--amplitude modal, the default)" in \
        result["report"]
    # A table without slip (the truth's linear frequency and a flat 0.3 % damping at amplitudes
    # where the joint barely slips), the structure's own damping fitted: said, and Fs not stated.
    flat = [(a, fr, 0.003 * (1 + 0.01 * (-1) ** i)) for i, (a, fr) in
            enumerate(zip(q["modal_amplitude"], q["ringdown_frequency_hz"]))]
    with open(d / "flat.csv", "w") as f:
        f.write("amplitude,frequency_hz,damping_ratio\n")
        for a, _, z in flat:
            f.write(f"{a * 1e-6!r},{flat[0][1]!r},{z!r}\n")
    flat_fit = jointlab.update_iwan(str(d / "start.toml"), "iwan.j", 1, [str(d / "flat.csv")],
                                    linear_damping="fit", evaluations=400)
    assert flat_fit["no_slip"], flat_fit["report"]
    assert "no slip in these data" in flat_fit["report"]
    assert flat_fit["parameters"]["Fs"]["relative_std"] is None
    assert flat_fit["parameters"]["Fs"]["note"] == "not identified: no slip in the data"
    assert_close(flat_fit["parameters"]["modal_ratio"]["final"], 0.003, 0.01)
    # Nothing printed: these fits' local solves meet points QSMA cannot evaluate, which Ceres
    # logged through glog ("Terminating: Residual and Jacobian evaluation failed") on stderr.
    assert capfd.readouterr().err == ""
    with pytest.raises(jointlab.InputError, match="--mode 2: model mode 2 does not exist"):
        jointlab.update_iwan(str(d / "start.toml"), "iwan.j", 2, [str(d / "bb.csv")])
    (d / "neg.csv").write_text("amplitude,frequency_hz,damping_ratio\n1e-4,93.0,-1e-5\n")
    with pytest.raises(jointlab.InputError, match="neg.csv:2"):
        jointlab.update_iwan(str(d / "start.toml"), "iwan.j", 1, [str(d / "neg.csv")])


def test_update_iwan_holds_and_noise_evidence_as_the_command(tmp_path):
    # The one-mode model's own QSMA table with gamma and beta held (--gamma, --beta): the call
    # ends where the command does (10 digits, as parameters.csv), the held ones at their values;
    # the noise note's evidence (the largest third's share of the chi-square, at least 1/3 by
    # its definition) and the misfit flag are returned; the command's refusals are its own.
    d = tmp_path
    q = one_mode_iwan(d, points=40)
    r = run("update-iwan", d / "start.toml", "--set", "j", "--mode", "1", "--backbone",
            d / "bb.csv", "--evaluations", "200", "--gamma", "1.1", "--beta", "0.5",
            "--linear-damping", "fit", "--linear-damping-max", "0.01", "--optimizer", "paper-log",
            "--compare", "secant", "--out", d / "cli")
    assert r.returncode == 0, r.stderr
    cli = read_parameters(d / "cli")
    # pathlib paths and a numpy integer as the mode (a loop over np.arange gives them: refused
    # before as 'expected an int').
    result = jointlab.update_iwan(d / "start.toml", "j", np.int64(1), [d / "bb.csv"],
                                  evaluations=200, gamma=1.1, beta=0.5, linear_damping="fit",
                                  linear_damping_max=0.01, threads=1, optimizer="paper-log",
                                  compare="secant", out=d / "py" / "new" / "model.toml")
    assert result["report"] == r.stdout
    assert_iwan_parameters_as_file(result, cli)
    for name in ("Fs", "Kt", "chi", "beta", "gamma"):
        assert_close(result["parameters"][name]["initial"], float(cli[name]["initial"]))
        assert_close(result["parameters"][name]["final"], float(cli[name]["final"]))
        assert result["parameters"][name]["held"] == (cli[name]["held"] == "1")
    for name in ("Fs", "Kt", "chi", "beta", "gamma", "modal_ratio"):  # the file's column
        assert result["parameters"][name]["identifiable"] == (cli[name]["identifiable"] == "1")
    assert_close(result["parameters"]["gamma"]["final"], 1.1)  # held there, as parameters.csv
    assert result["parameters"]["beta"]["final"] == 0.5 and result["parameters"]["Kt"]["held"]
    assert_close(result["parameters"]["modal_ratio"]["final"],
                 float(cli["modal_ratio"]["final"]))
    assert (d / "py" / "new" / "model.toml").read_text() == (d / "cli" / "model.toml").read_text()
    assert 1 / 3 <= result["amplitude_share"] <= 1
    assert result["misfit"] == ("WARNING the model does not describe" in result["report"])
    # The truth's own curve with 1.5e-3 frequency noise stated as 1.5e-4: the report's note that
    # the residuals look like noise, and its evidence returned (serial correlation under 0.3,
    # no third of the points, by amplitude, holding much more than 1/3 of the chi-square).
    rng = np.random.default_rng(3)
    with open(d / "noisy.csv", "w") as f:
        f.write("amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std\n")
        for a, fr, z in zip(q["modal_amplitude"], q["ringdown_frequency_hz"],
                            q["ringdown_damping_ratio"]):
            f.write(f"{a!r},{fr * (1 + 1.5e-3 * rng.standard_normal())!r},"
                    f"{z * (1 + 0.02 * rng.standard_normal())!r},{fr * 1.5e-4!r},{z * 0.02!r}\n")
    noisy = jointlab.update_iwan(d / "truth.toml", "j", 1, [d / "noisy.csv"], evaluations=300)
    assert "spread evenly over the amplitudes, as noise is" in noisy["report"]
    assert noisy["misfit"] and noisy["noise_correlation"] < 0.3
    assert 1 / 3 <= noisy["amplitude_share"] < 0.5
    for kwargs, message in (({"gamma": 0.0}, "--gamma 0: must be a finite number > 0"),
                            ({"beta": -1.0}, "--beta -1: must be a finite number >= 0"),
                            ({"linear_damping_max": 1.5}, "--linear-damping-max 1.5: must be in"),
                            ({"threads": -1}, "--threads -1: must be in"),
                            ({"optimizer": "ga"}, "--optimizer ga: expected paper"),
                            ({"compare": "tangent"}, "--compare tangent: expected matched")):
        with pytest.raises(jointlab.InputError, match=message):
            jointlab.update_iwan(str(d / "start.toml"), "j", 1, [str(d / "bb.csv")], **kwargs)
    with pytest.raises(jointlab.InputError, match="--set spring.k: update-iwan updates an Iwan"):
        jointlab.update_iwan(str(d / "start.toml"), "spring.k", 1, [str(d / "bb.csv")])


def test_update_iwan_fits_stepped_sine_with_the_hits_as_the_command(tmp_path):
    # The one-mode truth struck (`simulate`, 200 N) and processed, and ten of its own QSMA
    # steady-state points as a `stepped-sine` output folder (velocity at the sensor, q 2 pi f for
    # the unit mass): stepped_sine= fits them with the hit as --stepped-sine does, the same
    # parameters (10 digits) and report (the slip screen a progress line; the hit alone, microslip
    # only, ends at the top of the Fs range, 1800 N, against 60.0 N with the sine). A Pareto
    # front at two gammas (--pareto) comes with it, as pareto.csv.
    d = tmp_path
    q = one_mode_iwan(d, points=40)
    r = run("simulate", d / "truth.toml", "--impact", "0", "--force", "200", "--duration", "2",
            "--fs", "2048", "--modal-damping", "0.001", "--out", d / "hit.csv", "--quiet")
    assert r.returncode == 0, r.stderr
    r = run("process", d / "hit.csv", "--band", "60:130", "--out", d / "p")
    assert r.returncode == 0, r.stderr
    (d / "sensors.csv").write_text("channel,dof\nacc_0,0\n")
    (d / "sine").mkdir()
    (d / "sine" / "summary.json").write_text(json.dumps({
        "program": "jointlab stepped-sine", "amplitude_quantity": "velocity",
        "amplitude_unit": "m/s",
        "files": [{"file": "sweeps.csv", "output": "sweeps.backbone.csv", "levels": []}]}))
    with open(d / "sine" / "sweeps.backbone.csv", "w") as f:
        f.write("amplitude,frequency_hz,damping_ratio,frequency_std_hz,damping_std\n")
        for a, fr, z in list(zip(q["modal_amplitude"], q["frequency_hz"],
                                 q["harmonic_damping_ratio"]))[::4]:
            f.write(f"{a * 2 * np.pi * fr!r},{fr!r},{z!r},{fr * 1e-4!r},{z * 0.02!r}\n")
    r = run("update-iwan", d / "start.toml", "--set", "j", "--mode", "1", "--measured", d / "p",
            "--sensors", d / "sensors.csv", "--stepped-sine", d / "sine", "--linear-damping",
            "fit", "--evaluations", "200", "--pareto", "0.9,1.1", "--out", d / "cli")
    assert r.returncode == 0, r.stderr
    cli = read_parameters(d / "cli")
    lines = []
    both = jointlab.update_iwan(d / "start.toml", "j", 1, measured=d / "p",
                                sensors=d / "sensors.csv", stepped_sine=[d / "sine"],
                                linear_damping="fit", evaluations=200, pareto=[0.9, 1.1],
                                progress=lines.append)
    assert_iwan_parameters_as_file(both, cli)
    assert lines[0].startswith("slip screen") and "stepped sine" in lines[0]
    assert lines[0] + both["report"] == r.stdout
    with open(d / "cli" / "pareto.csv", newline="") as f:
        front = list(csv.DictReader(f))
    assert [p["gamma"] for p in both["pareto"]] == [0.9, 1.1]
    for p, row in zip(both["pareto"], front):
        for name in ("Fs", "Kt", "chi", "beta", "linear_error", "backbone_cost"):
            assert_close(p[name], float(row[name]))
        assert p["dominated"] == (row["dominated"] == "1")
        assert_close(p["mode_errors"][0], float(row["linear_error1"]))
    with pytest.raises(jointlab.InputError, match="--pareto 0: gamma values must be"):
        jointlab.update_iwan(d / "start.toml", "j", 1, measured=d / "p", sensors=d / "sensors.csv",
                             pareto=[1.0, 0.0])
    with pytest.raises(jointlab.InputError, match="--stepped-sine-mode -1"):
        jointlab.update_iwan(d / "start.toml", "j", 1, measured=d / "p", sensors=d / "sensors.csv",
                             stepped_sine=[d / "sine"], stepped_sine_mode=-1)


def test_build_model_writes_the_commands_folder_and_returns_its_model(tmp_path):
    # A coarse beam-element riveted beam (156 DOFs, 0.06 s): the folder the call writes is the
    # command's, byte for byte (the description given by the same path), and the Model returned
    # is that folder's model.toml, its modes the same numbers as the command's folder's, bit for
    # bit. modes= is --modes; progress gets the library's step lines.
    description = tmp_path / "beam.toml"
    description.write_text(
        '[strips]\nlength = 0.2\nwidth = 0.02\nthickness = 0.002\n\n'
        '[mesh]\nelement = "beam"\nsize = 0.02\n\n[rivets]\ncount = 2\n\n'
        '[reduction]\nfixed_interface_modes = 8\n\n'
        '[[sensor]]\nlabel = 9001\nstrip = 1\nx = 0.0\ny = 0.0\ncomponents = ["z"]\n')
    r = run("build-model", description, "--out", tmp_path / "cli", "--modes", "6", "--quiet")
    assert r.returncode == 0, r.stderr
    lines = []
    model = jointlab.build_model(description, tmp_path / "py", modes=6, progress=lines.append)
    assert isinstance(model, jointlab.Model)
    assert pathlib.Path(model.path) == tmp_path / "py" / "model.toml"
    for name in ("M.mtx", "K.mtx", "dofs.csv", "model.toml"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert model.dofs == 25 + 6  # 2 rivets x 2 strips x 6 + the sensor's z, and 6 modes
    assert "9001:3" in model.dof_labels
    assert np.array_equal(model.modes(12), jointlab.Model(tmp_path / "cli" / "model.toml").modes(12))
    assert any("fixed-interface modes: 6 lowest" in line for line in lines)
    with pytest.raises(jointlab.InputError, match=r"^--modes -1: must be in \[0, "):
        jointlab.build_model(description, tmp_path / "bad", modes=-1)
    with pytest.raises(jointlab.InputError, match="missing.toml"):
        jointlab.build_model(tmp_path / "missing.toml", tmp_path / "bad")
    assert not (tmp_path / "bad").exists()
    # Ctrl-C during the build (the signal taken at its first checkpoint after the first step's
    # line): KeyboardInterrupt, and `out` is not written.
    def interrupt(line):
        if "generating" in line:
            os.kill(os.getpid(), signal.SIGINT)
    with pytest.raises(KeyboardInterrupt):
        jointlab.build_model(description, tmp_path / "stopped", progress=interrupt)
    assert not (tmp_path / "stopped").exists()


def test_simulate_returns_the_commands_record(tmp_path):
    # The two-mass Iwan model struck at mass 1 (0.5 s at 2048 Hz, 10 substeps, 0.02 s): both
    # masses, 1 % noise of seed 7 and the hammer channel. The record returned holds the numbers
    # of the command's file bit for bit (its CSV prints each sample's shortest round-trip text, so
    # no tolerance is needed; the brief asked for 1e-12), and `out` writes that file byte for
    # byte. A jointlab.Model or its file, an int or a 'node:component' DOF: the same record.
    model_file = two_mass_model(tmp_path)
    args = ["--impact", "0", "--force", "50", "--duration", "0.5", "--fs", "2048", "--sensors",
            "0", "--sensors", "1", "--noise", "0.01", "--seed", "7", "--force-channel"]
    r = run("simulate", model_file, *args, "--out", tmp_path / "cli.csv", "--quiet")
    assert r.returncode == 0, r.stderr
    cli = jointlab.read_record(tmp_path / "cli.csv")
    lines = []
    rec = jointlab.simulate(model_file, 0, force=50, duration=0.5, fs=2048, sensors=[0, 1],
                            noise=0.01, seed=7, force_channel=True, out=tmp_path / "py.csv",
                            progress=lines.append)
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    assert rec["channels"] == ["acc_0", "acc_1", "hammer"] == cli["channels"]
    assert rec["units"] == cli["units"]
    # The record's own metadata: the file's, but for the fs and t0 the writer adds (and the case
    # of force_N, which the reader lowers).
    assert {k.lower(): v for k, v in rec["metadata"].items()} == {
        k: v for k, v in cli["metadata"].items() if k not in ("fs", "t0")}
    assert rec["sample_rate_hz"] == 2048 and rec["t0_s"] == 0
    assert np.array_equal(rec["time_s"], cli["time_s"])
    for name in rec["channels"]:
        assert np.array_equal(rec["data"][name], cli["data"][name]), name
    assert "energy" in rec["report"] and len(lines) >= 10
    again = jointlab.simulate(jointlab.Model(model_file), "0", 50, 0.5, 2048, sensors=(0, "1"),
                              noise=0.01, seed=np.uint64(7), force_channel=True)
    for name in rec["channels"]:
        assert np.array_equal(again["data"][name], rec["data"][name]), name
    # The impact DOF alone by default, and the command's messages for bad input.
    assert jointlab.simulate(model_file, 1, 50, 0.5, 2048)["channels"] == ["acc_1"]
    with pytest.raises(jointlab.InputError, match="simulate: duration must be > 0"):
        jointlab.simulate(model_file, 0, 50, -1.0, 2048)
    with pytest.raises(jointlab.InputError, match="--impact"):
        jointlab.simulate(model_file, 5, 50, 0.5, 2048)
    with pytest.raises(jointlab.InputError, match=r"^--seed -1: must be in \[0, 18446744073709551615\]"):
        jointlab.simulate(model_file, 0, 50, 0.5, 2048, noise=0.01, seed=-1)
    with pytest.raises(TypeError, match="model: expected a model file"):
        jointlab.simulate(3.5, 0, 50, 0.5, 2048)


def test_stepped_sine_equals_the_command_line(tmp_path):
    # The Brake-Reuss beam's twelve sweeps (.mat, 0.3 s): one SineBackbone, its arrays the
    # command's CSV columns within 1e-9 (the CSV keeps 10 significant digits) in the CSV's order,
    # and `out` the command's folder, byte for byte (the folder update_iwan's stepped_sine=
    # reads). A line per level goes to progress, as the command's stderr.
    sweeps = RECORD.parent / "forced_frequency_responses.mat"
    r = run("stepped-sine", sweeps, "--damping-model", "viscous", "--out", tmp_path / "cli")
    assert r.returncode == 0, r.stderr
    lines = []
    result = jointlab.stepped_sine(sweeps, damping_model="viscous", out=tmp_path / "py",
                                   progress=lines.append)
    assert len(result) == 1
    b = result[0]
    assert isinstance(b, jointlab.SineBackbone) and b.file == str(sweeps)
    assert (b.amplitude_quantity, b.amplitude_unit) == ("velocity", "m/s")
    for name in ("summary.json", "forced_frequency_responses.backbone.csv"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    csv_columns = read_csv(tmp_path / "cli" / "forced_frequency_responses.backbone.csv")
    assert list(vars(b)) == list(csv_columns)
    for name, column in csv_columns.items():
        assert_close(getattr(b, name), column)
    assert len(b.reports) == 12 and lines == [f"{sweeps} {report}" for report in b.reports]
    assert lines == r.stderr.splitlines()
    assert np.all(np.diff(b.amplitude) >= 0)
    copy = pickle.loads(pickle.dumps(b))
    assert copy.reports == b.reports and np.array_equal(copy.damping_ratio, b.damping_ratio)
    with pytest.raises(jointlab.InputError, match="^--damping-model coulomb: expected hysteretic"):
        jointlab.stepped_sine(sweeps, damping_model="coulomb")
    with pytest.raises(jointlab.InputError, match=r"^--residual-terms 3: must be in \[0, 2\]"):
        jointlab.stepped_sine(sweeps, residual_terms=3)
    with pytest.raises(jointlab.InputError, match="share the name"):
        jointlab.stepped_sine([sweeps, sweeps])
