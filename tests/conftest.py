import os
import sys

# tests/ holds helpers (taylor.py) imported by name.
sys.path.insert(0, os.path.dirname(__file__))
