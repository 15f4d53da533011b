"""dalembert from Python, cell by cell (``# %%`` cells run in Jupyter, VS Code or as a script).

Run it as ``python docs/api_example.py [OUT_DIR]``; ``tests/test_api.py`` runs it as written.
"""

# %% Run a small selection: one case, two step sizes, the reference engine (a few seconds)
import sys
import tempfile

from dalembert.harness import api

out = sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="dalembert-")
runs = api.run(cases=["free_top"], engines=["reference"], integrators=["rk4", "euler"], dts=[1e-2, 5e-3],
               params={"t_final": 1.0}, out=f"{out}/top", jobs=1)
print(runs[["engine", "settings", "status", "err_orientation_max", "drift_energy", "wall_s_median", "verdict"]])

# %% Inputs are checked as the command line checks them, before anything is written
try:
    api.run(cases=["free_top"], engines=["reference"], params={"t_finl": 1.0}, out=f"{out}/typo")
except ValueError as refused:
    print("refused:", refused)  # --param t_finl: no selected case has this parameter — did you mean 't_final'?

# %% The same records from the store on disk, any time later
store = api.load(runs.attrs["store"])
best = min((r for r in store.records() if r.ok), key=lambda r: r.max_error("orientation"))
print("most accurate:", best.settings_label, f"{best.max_error('orientation'):.2e} rad")

# %% What the report opens with, as data
for case in api.findings(store):
    print("\n".join(case.sentences))
    for hazard in case.hazards:
        print(f"[{hazard.kind}] {hazard.text}")

# %% The report itself: report.html (self-contained), report.md, summary.csv
html_path, md_path, csv_path = api.report(store)
print("report:", html_path)

# %% Every sample of every run as one long-format table
samples = api.trajectories(store, integrator="rk4")
top = samples[(samples.kind == "body") & (samples.dt == 5e-3)]
print(top[["t", "qw", "qx", "qy", "qz"]].tail(3))

# %% Compare two stores (here the store with itself: nothing changed)
comparison = api.compare(store, store)
print("regressed:", comparison.regressed, "| runs compared:", len(comparison.changes))
