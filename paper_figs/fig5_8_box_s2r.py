#!/usr/bin/env python3
"""Thesis Fig. 5.8: the box path on the twins, without and with the sim-to-real layer.

Usage: fig5_8_box_s2r.py RESULTS_DIR

Same inputs and panels as fig5_7_flower_s2r.py (whose plotting it uses); writes
RESULTS_DIR/fig5_8_box_s2r.png. Exit status 2 with a message on stderr if a file is missing or
malformed.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import importlib  # noqa: E402

if __name__ == "__main__":
    importlib.import_module("fig5_7_flower_s2r").plot("fig5_8_box_s2r", sys.argv, __doc__)
