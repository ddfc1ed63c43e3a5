#!/usr/bin/env python3
"""Ablation of Fig. 3.7: the same progressive remeshing with the re-tessellated chamber's rest shape
pulled back to the original chamber (chamber_rest = original) instead of its remeshed shape.

Usage: fig3_7_original_rest.py RESULTS_DIR

Reads the files `softkin run experiments/configs/fig3_7_original_rest.json` writes (the same as
fig3_7_twisting_remesh's) and draws the same panels into RESULTS_DIR/fig3_7_original_rest.png.
Exit status 2 with a message on stderr if a file is missing or malformed.
"""
import sys

import fig3_7_twisting_remesh as fig37

if __name__ == "__main__":
    fig37.NAME = "fig3_7_original_rest"
    sys.exit(fig37.main(sys.argv))
