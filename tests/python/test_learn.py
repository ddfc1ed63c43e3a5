"""Tests of softkin's learning pipeline in Python: a dataset written and resumed through
softkin.dataset, networks trained by softkin.train, and IK on the learned kinematics, plus the
in-process command line's errors."""

import os

import numpy as np
import pytest

import softkin


@pytest.fixture(scope="module")
def nets_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("learn")
    csv = d / "three_chamber.csv"
    assert softkin.dataset(csv, "three_chamber", res=3, grid=4, jacobian="implicit",
                           quiet=True) == 0
    return d, csv


def test_dataset_resumes_to_the_same_bytes(nets_dir, tmp_path):
    d, csv = nets_dir
    full = csv.read_bytes()
    lines = full.decode().splitlines(keepends=True)
    assert len(lines) == 1 + 4 ** 3  # header + grid^3 samples
    # A run killed after 20 samples (file cut there, half a line more): the rerun completes it.
    part = tmp_path / "part.csv"
    part.write_text("".join(lines[:21]) + lines[21][:10])
    (tmp_path / "part.csv.json").write_bytes((d / "three_chamber.csv.json").read_bytes())
    assert softkin.dataset(part, "three_chamber", res=3, grid=4, jacobian="implicit",
                           quiet=True) == 0
    assert part.read_bytes() == full


def test_trained_networks_do_ik_close_to_the_simulator(nets_dir, tmp_path):
    d, csv = nets_dir
    nets = softkin.train(csv, tmp_path / "nets", what="fk,jac", hidden=(12,), hidden_jac=(12,),
                         epochs=200, seed=1, quiet=True)
    assert isinstance(nets, softkin.Kinematics)
    assert nets.point_names == ["tip"] and nets.num_actuators == 3
    assert os.path.exists(tmp_path / "nets" / "nets.json")
    again = softkin.load_nets(tmp_path / "nets")
    c = np.array([1.5, 1.2, 1.0])
    np.testing.assert_array_equal(nets.p(c), again.p(c))
    sim = softkin.SimulatorKinematics(softkin.robot("three_chamber", res=3), points=["tip"])
    target = sim.p(c)[0]
    # The network's own prediction is within a few mm of the simulator over a 139 mm workspace.
    assert np.linalg.norm(nets.p(c)[0] - target) < 5.0
    r = softkin.ik.solve(nets, target, method="gauss-newton")
    assert r["converged"], r["message"]
    assert r["fk_solves"] >= 1 and r["inverted_elements"] == 0
    assert np.linalg.norm(sim.p(r["c"])[0] - target) < 5.0


def test_command_errors_are_value_errors_with_the_option_named(tmp_path):
    with pytest.raises(ValueError, match="--grid"):
        softkin.dataset(tmp_path / "x.csv", "three_chamber", grid=0)
    with pytest.raises(ValueError, match="no_such_robot|unknown robot"):
        softkin.dataset(tmp_path / "x.csv", "no_such_robot", grid=3)
    with pytest.raises(ValueError, match="--dataset|missing.csv"):
        softkin.train(tmp_path / "missing.csv", tmp_path / "nets")
    with pytest.raises(RuntimeError, match="nets.json"):
        softkin.load_nets(tmp_path)
    assert softkin.cli(["robots"]) == 0
