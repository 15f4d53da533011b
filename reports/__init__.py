"""Reports: read stored results only, never run an engine (the reports issue fills this)."""
