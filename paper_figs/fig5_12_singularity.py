#!/usr/bin/env python3
"""Thesis Fig. 5.12: an 'L' path through the near-singular straight pose of finger_manipulator.

Usage: fig5_12_singularity.py RESULTS_DIR

Same inputs and panels as fig5_10_eight.py (whose plotting it uses); writes
RESULTS_DIR/fig5_12_singularity.png. Exit status 2 with a message on stderr if a file is missing
or malformed.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import importlib  # noqa: E402

if __name__ == "__main__":
    importlib.import_module("fig5_10_eight").plot("fig5_12_singularity", sys.argv, __doc__)
