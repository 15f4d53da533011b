"""Engine adapters: one module per engine (the run-matrix issue defines the contract)."""
