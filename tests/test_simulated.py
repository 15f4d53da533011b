"""What each engine simulated beyond the scene (``reports.simulated``): audits with different keys per engine in
one table — number type, gravity where it is not the scene's, loop softness, regularisation, gains."""

from types import SimpleNamespace

from dalembert.reports.simulated import TEXT_CHARS, simulated

SCENE_G = (0.0, 0.0, -9.81)


def _run(engine, audit, case="four_bar", options=""):
    return SimpleNamespace(engine=engine, audit=audit, case=case, ok=True, options_label=options, options_text=options)


def test_audits_with_their_own_keys_compare_in_one_row_each():
    runs = [_run("mjx", {"precision": "float32", "gravity_device": [0.0, 0.0, -9.8100004196167],
                         "gravity": [0.0, 0.0, -9.81], "loop_softness": "soft equality", "loop_solref": [0.002, 1.0],
                         "backend": "cpu"}),
            _run("mjx", {"precision": "float64", "gravity_device": [0.0, 0.0, -9.81]}, case="pendulum",
                 options="precision=float64"),
            _run("pinocchio", {"gravity": [0.0, 0.0, -9.81], "proximal": {"mu": 7.5e-10},
                               "drift_correction": {"Kp": 900.0, "Kd": 60.0, "method": "Baumgarte"}}),
            _run("pinocchio", {"gravity": [0.0, 0.0, 0.0]}, case="free_top")]  # a case without gravity
    rows = {s.engine: s.values for s in simulated(runs, lambda r: SCENE_G if r.case != "free_top" else (0, 0, 0))}
    mjx, pin = rows["mjx"], rows["pinocchio"]
    assert mjx["number type"][1] == "float32 (defaults) | float64 (precision=float64)"
    assert mjx["gravity as stored (m/s²)"][1] == "[0.0, 0.0, -9.8100004196167], the scene [0.0, 0.0, -9.81]"
    assert mjx["loop constraints"][1] == "soft equality" and mjx["stabilisation gains"][1] == "loop_solref [0.002, 1.0]"
    assert mjx["where it ran"][1] == "cpu"
    assert pin["gravity as stored (m/s²)"][1] == "as the scene"
    assert pin["regularisation"][1] == "mu 7.5e-10" and pin["stabilisation gains"][1] == "Kp 900.0; Kd 60.0"
    assert pin["loop constraints"][1] == "Baumgarte" and pin["number type"][1] == ""


def test_a_long_audit_text_is_cut_in_the_cell_and_whole_on_hover():
    text = "x" * (2 * TEXT_CHARS)
    (row,) = simulated([_run("exudyn", {"known_issue": text})], lambda r: SCENE_G)
    short, full = row.values["known issue"]
    assert full == text and len(short) == TEXT_CHARS and short.endswith("…")
