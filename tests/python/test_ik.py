"""Tests of softkin's kinematics and IK in Python: the simulator, PCC and Python-defined
kinematics under the C++ IK methods, and the errors they report."""

import numpy as np
import pytest

import softkin


class Linear(softkin.Kinematics):
    """p = A c + b for one point: IK has the exact answer c* = A^+ (target - b)."""

    def __init__(self):
        super().__init__(["tip"], [0.0, 0.0], [1.0, 1.0], name="linear")
        self.A = np.array([[10.0, 0.0], [0.0, 20.0], [1.0, 1.0]])
        self.b = np.array([1.0, 2.0, 3.0])
        self.calls = 0

    def compute(self, c, with_jacobian):
        self.calls += 1
        p = (self.A @ c + self.b).reshape(1, 3)
        return (p, self.A.copy()) if with_jacobian else p


@pytest.fixture(scope="module")
def three_chamber():
    return softkin.robot("three_chamber", res=3)


def test_python_kinematics_is_driven_by_every_gradient_method():
    target = np.array([1.0 + 5.0, 2.0 + 4.0, 3.0 + 0.7])  # c* = (0.5, 0.2)
    for method in ["softls", "gauss-newton", "nlopt-lbfgs", "nlopt-slsqp", "broyden"]:
        kin = Linear()
        r = softkin.ik.solve(kin, target, method=method, lambda_mm=1e-3, max_iterations=200,
                             max_evaluations=2000)
        assert r["converged"], (method, r["message"])
        np.testing.assert_allclose(r["c"], [0.5, 0.2], atol=1e-3, err_msg=method)
        assert r["error_mm"] <= 1e-3
        assert kin.total_fk_solves == kin.calls > 0


def test_python_kinematics_bounds_and_failures_are_reported():
    kin = Linear()
    # A target outside the box: the answer is on the bound, not converged.
    r = softkin.ik.solve(kin, [1 + 20.0, 2 + 4.0, 3 + 2.2], method="gauss-newton")
    assert not r["converged"]
    assert r["c"][0] == pytest.approx(1.0)

    class Broken(softkin.Kinematics):
        def __init__(self):
            super().__init__(["tip"], [0.0], [1.0])

        def compute(self, c, with_jacobian):
            raise ValueError("the model is not loaded")

    with pytest.raises(RuntimeError, match="the model is not loaded"):
        Broken().p([0.5])
    r = softkin.ik.solve(Broken(), [0, 0, 0])
    assert not r["converged"] and r["termination"] == "kinematics-failure"

    class WrongShape(softkin.Kinematics):
        def __init__(self):
            super().__init__(["a", "b"], [0.0], [1.0])

        def compute(self, c, with_jacobian):
            return np.zeros((1, 3)), np.zeros((6, 1))

    with pytest.raises(RuntimeError, match="p: expected 2 rows"):
        WrongShape().p([0.5])
    with pytest.raises(ValueError, match="lower < upper"):
        softkin.Kinematics(["tip"], [1.0], [0.0])
    with pytest.raises(ValueError, match="outside|range|bound"):
        kin.p([2.0, 0.0])


def test_bounds_keep_ik_inside_a_narrower_box():
    kin = Linear()
    target = [1.0 + 5.0, 2.0 + 4.0, 3.0 + 0.7]  # c* = (0.5, 0.2)
    r = softkin.ik.solve(kin, target, method="gauss-newton", bounds=[[0.0, 0.4], [0.0, 1.0]])
    assert not r["converged"]
    assert r["c"][0] == pytest.approx(0.4) and 0.0 <= r["c"][1] <= 1.0
    r = softkin.ik.solve(kin, target, method="gauss-newton", bounds=[[0.3, 0.7], [0.1, 0.3]])
    assert r["converged"]
    with pytest.raises(ValueError, match=r"bounds\[0\]: expected min < max within"):
        softkin.ik.solve(kin, target, bounds=[[0.5, 1.5], [0.0, 1.0]])
    with pytest.raises(ValueError, match="bounds: expected one"):
        softkin.ik.solve(kin, target, bounds=[[0.0, 1.0]])


def test_simulator_ik_reaches_a_point_it_produced(three_chamber):
    kin = softkin.SimulatorKinematics(three_chamber, points=["tip"])
    c_true = np.array([1.35, 1.1, 1.0])
    target = kin.p(c_true)[0]
    for method in ["softls", "gauss-newton"]:
        kin.reset()
        r = softkin.ik.solve(kin, target, method=method)
        assert r["converged"], r["message"]
        assert r["error_mm"] <= 0.2
        assert r["inverted_elements"] == 0
        assert np.linalg.norm(kin.p(r["c"])[0] - target) <= 0.2 + 1e-6


def test_follow_a_reachable_path_with_the_implicit_jacobian(three_chamber):
    kin = softkin.SimulatorKinematics(three_chamber, jacobian="implicit", points=["tip"])
    t = np.linspace(0, 2 * np.pi, 7)[:-1]
    cs = np.stack([1.2 + 0.1 * np.cos(t), 1.2 + 0.1 * np.cos(t - 2.1), 1.2 + 0.1 * np.cos(t + 2.1)],
                  axis=1)
    path = np.array([kin.p(c)[0] for c in cs])
    kin.reset()
    f = softkin.ik.follow(kin, path, method="gauss-newton", samples_per_axis=3)
    assert f["c"].shape == (6, 3) and f["reached"].shape == (6, 3)
    assert f["converged"].all(), f["termination"]
    assert f["num_converged"] == 6 and f["max_error_mm"] <= 0.2
    np.testing.assert_allclose(np.linalg.norm(f["reached"] - path, axis=1), f["error_mm"],
                               atol=1e-9)


def test_pcc_kinematics_matches_its_closed_form():
    pcc = softkin.PccKinematics(length=100.0)
    assert pcc.num_actuators == 3 and pcc.point_names[0] == "tip"
    np.testing.assert_allclose(pcc.p([0, 0, 0])[0], [0, 0, 100.0], atol=1e-9)
    # J against central differences of p.
    c = np.array([3.0, 1.0, 0.5])
    J = pcc.J(c)
    h = 1e-6
    for a in range(3):
        e = np.zeros(3)
        e[a] = h
        col = (pcc.p(c + e) - pcc.p(c - e)).reshape(-1) / (2 * h)
        np.testing.assert_allclose(J[:, a], col, rtol=1e-5, atol=1e-6)
    r = softkin.ik.solve(pcc, pcc.p([4.0, 1.0, 0.0])[0], method="gauss-newton")
    assert r["converged"]


def test_ik_option_errors_name_the_option(three_chamber):
    kin = Linear()
    with pytest.raises(ValueError, match="method: expected one of: softls"):
        softkin.ik.solve(kin, [0, 0, 0], method="newton")
    with pytest.raises(ValueError, match="lambda_mm"):
        softkin.ik.solve(kin, [0, 0, 0], lambda_mm=-1)
    with pytest.raises(ValueError, match=r"target \(x, y, z in mm\): expected 3 values"):
        softkin.ik.solve(kin, [0, 0])
    with pytest.raises(ValueError, match="tipp"):
        softkin.ik.solve(kin, [0, 0, 0], point="tipp")
    assert "softls" in softkin.ik.methods()
