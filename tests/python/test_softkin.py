"""Tests of the Python package softkin (python/): scenes, FK, Jacobians and kinematics with NumPy
arrays, the errors' messages, and solves from several Python threads. Run by ctest (python label)
with PYTHONPATH set to the build tree's python/ folder."""

import json
import os
import subprocess
import threading
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import softkin

SOURCE_DIR = os.environ.get("SOFTKIN_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))


@pytest.fixture(scope="module")
def finger():
    return softkin.robot("pneumatic_finger", res=5)


def voxel_bar(nx=6, ny=2, nz=2, h=1.0):
    """A bar of nx x ny x nz cubes of edge h, each split into 6 tets around its diagonal; the upper
    layer (z >= 1 cells) is tagged 1, the rest 0."""
    idx = lambda i, j, k: i + (nx + 1) * (j + (ny + 1) * k)
    verts = np.array([[i * h, j * h, k * h] for k in range(nz + 1) for j in range(ny + 1)
                      for i in range(nx + 1)], dtype=float)
    # Kuhn's split of the unit cube: 6 tets along the diagonal 0 -> 7.
    paths = [(1, 2, 4), (1, 4, 2), (2, 1, 4), (2, 4, 1), (4, 1, 2), (4, 2, 1)]
    elems, tags = [], []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                corner = lambda b: idx(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1))
                for p in paths:
                    a = 0
                    tet = [corner(0)]
                    for step in p:
                        a |= step
                        tet.append(corner(a))
                    elems.append(tet)
                    tags.append(1 if k >= nz // 2 else 0)
    return verts, np.array(elems), np.array(tags)


BAR_REGIONS = [{"tag": 0, "role": "body", "r_omega": 1.0},
               {"tag": 1, "role": "pneumatic", "name": "chamber", "min": 1, "max": 2}]
BAR_FIXED = [{"plane": {"point": [0, 0, 0], "normal": [1, 0, 0]}}]
BAR_MARKERS = [{"name": "tip", "box": {"min": [5.9, -1, -1], "max": [6.1, 3, 3]}}]


def test_robots_lists_every_generator_with_its_parameters():
    names = [r["name"] for r in softkin.robots()]
    assert "pneumatic_finger" in names and "three_chamber" in names
    bar = next(r for r in softkin.robots() if r["name"] == "bimaterial_bar")
    assert any(p["name"] for p in bar["params"])


def test_robot_errors_name_what_was_expected():
    with pytest.raises(ValueError, match="pneumatic_finger"):
        softkin.robot("no_such_robot")
    with pytest.raises(ValueError, match="res: expected an integer >= 1"):
        softkin.robot("pneumatic_finger", res=0)
    with pytest.raises(ValueError, match=r"\[5, 40\]"):
        softkin.robot("pneumatic_finger", res=2)


def test_scene_arrays_describe_the_mesh(finger):
    V, E, T = finger.vertices, finger.elements, finger.tags
    assert V.shape == (finger.num_vertices, 3) and V.dtype == np.float64
    assert E.shape == (finger.num_elements, 4) and E.dtype == np.int64
    assert T.shape == (finger.num_elements,)
    assert E.min() == 0 and E.max() == finger.num_vertices - 1
    assert finger.actuators[0]["name"] == "chamber"
    np.testing.assert_array_equal(finger.rest, [1.0])
    assert set(finger.markers) >= {"tip"}
    assert len(finger.fixed) > 0
    # Arrays are copies: changing one leaves the scene as it was.
    V[0] = 1e6
    assert finger.vertices[0, 0] != 1e6


def test_fk_rest_stays_at_rest_and_inflation_bends(finger):
    solver = softkin.FkSolver(finger, solver="lg-aa")
    rest = solver.solve(1.0)
    assert rest.converged and rest.status == "converged"
    np.testing.assert_allclose(rest.positions, finger.vertices, atol=1e-9)
    bent = solver.solve(3.0)
    assert bent.converged, bent.message
    assert bent.positions.shape == (finger.num_vertices, 3)
    assert not np.isnan(bent.positions).any()
    tip0 = finger.marker_positions(finger.vertices)["tip"]
    assert np.linalg.norm(bent.markers["tip"] - tip0) > 5.0
    assert 1.0 < bent.volume_ratios[0] <= 3.0
    assert bent.inverted_elements == 0
    # Warm start from the bent state: same equilibrium, fewer iterations.
    again = solver.solve([3.0], warm_start=bent.positions)
    assert again.converged and again.iterations < bent.iterations
    np.testing.assert_allclose(again.positions, bent.positions, atol=1e-3)


def test_newton_and_lg_aa_agree_through_python(finger):
    a = softkin.solve_fk(finger, 2.5, solver="lg-aa")
    b = softkin.solve_fk(finger, 2.5, solver="newton")
    assert a.converged and b.converged
    assert np.abs(a.positions - b.positions).max() < 1e-2


def test_a_state_with_inverted_elements_is_not_converged():
    bar = softkin.robot("bimaterial_bar", res=4)
    r = softkin.FkSolver(bar, solver="lg-aa", threads=1).solve([180.0, 40.0])
    assert r.status == "inverted" and not r.converged
    assert r.inverted_elements > 0 and "are inverted" in r.message


def test_options_are_the_scene_json_keys_with_its_messages(finger):
    solver = softkin.FkSolver(finger, solver="lg", max_iterations=50, threads=1)
    assert solver.options["solver"] == "lg" and solver.options["max_iterations"] == 50
    capped = solver.solve(3.0)
    assert capped.status == "iteration_cap" and not capped.converged
    with pytest.raises(ValueError, match="options.*max_iteratons"):
        softkin.FkSolver(finger, max_iteratons=5)
    with pytest.raises(ValueError, match="options.solver"):
        softkin.FkSolver(finger, solver="magic")
    with pytest.raises(ValueError, match=r"c \(one value per actuator\): expected 1 value"):
        softkin.FkSolver(finger).solve([1.0, 2.0])
    with pytest.raises(ValueError, match="warm_start: expected 1085 rows"):
        softkin.FkSolver(finger).solve(2.0, warm_start=np.zeros((3, 3)))


def test_write_vtu_gives_a_paraview_file(finger, tmp_path):
    r = softkin.solve_fk(finger, 2.0)
    path = tmp_path / "bent.vtu"
    r.write_vtu(str(path))
    root = ET.parse(path).getroot()
    assert root.tag == "VTKFile"
    piece = root.find(".//Piece")
    assert int(piece.get("NumberOfPoints")) == finger.num_vertices
    assert int(piece.get("NumberOfCells")) == finger.num_elements
    with pytest.raises(Exception, match="no_such_folder"):
        r.write_vtu(str(tmp_path / "no_such_folder" / "x.vtu"))


def test_implicit_jacobian_matches_differences(finger):
    solver = softkin.FkSolver(finger, tolerance=1e-9)
    imp = solver.jacobian(2.0)
    fd = solver.jacobian(2.0, mode="fd-warm")
    assert imp["dX"].shape == (finger.num_vertices, 3, 1)
    tip_imp, tip_fd = imp["markers"]["tip"], fd["markers"]["tip"]
    assert tip_imp.shape == (3, 1)
    assert np.linalg.norm(tip_imp) > 1.0
    assert np.linalg.norm(tip_imp - tip_fd) < 1e-2 * np.linalg.norm(tip_imp)
    # The marker Jacobian is the mean of its vertices' rows.
    tip = finger.markers["tip"]
    np.testing.assert_allclose(imp["dX"][tip].mean(axis=0), tip_imp, rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="mode: expected one of"):
        solver.jacobian(2.0, mode="exact")


def test_simulator_kinematics_p_and_j(finger):
    kin = softkin.SimulatorKinematics(finger, jacobian="implicit", points=["tip"])
    assert kin.point_names == ["tip"] and kin.num_actuators == 1
    p = kin.p(2.0)
    J = kin.J(2.0)
    assert p.shape == (1, 3) and J.shape == (3, 1)
    jac = softkin.FkSolver(finger).jacobian(2.0)
    np.testing.assert_allclose(J[:, 0], jac["markers"]["tip"][:, 0], rtol=1e-3, atol=1e-4)
    with pytest.raises(ValueError, match=r"value 50 is outside its range \[1, 10\]"):
        kin.p(50.0)


def test_scene_from_arrays_builds_a_bar_that_bends_away_from_its_chamber():
    V, E, T = voxel_bar()
    scene = softkin.scene_from_arrays(V, E, T, regions=BAR_REGIONS, fixed=BAR_FIXED,
                                      markers=BAR_MARKERS, name="bar")
    assert scene.name == "bar" and scene.num_elements == len(E)
    assert scene.actuators[0]["regions"] == [1]
    r = softkin.solve_fk(scene, 1.6)
    assert r.converged, r.message
    tip0 = scene.marker_positions(scene.vertices)["tip"]
    assert r.markers["tip"][2] < tip0[2] - 0.3  # the tip goes down (-z), away from the chamber
    assert r.inverted_elements == 0
    # Regions as a dict tag -> role (or entry) give the same scene.
    same = softkin.scene_from_arrays(
        V, E, T, regions={0: {"role": "body", "r_omega": 1.0},
                          1: {"role": "pneumatic", "name": "chamber", "min": 1, "max": 2}},
        fixed=BAR_FIXED, markers=BAR_MARKERS)
    np.testing.assert_array_equal(softkin.solve_fk(same, 1.6).positions, r.positions)
    assert softkin.scene_from_arrays(V, E, T, regions={0: "body", 1: "body"},
                                     fixed=BAR_FIXED).num_actuators == 0


def test_scene_from_arrays_refuses_bad_arrays_clearly():
    V, E, T = voxel_bar()
    kw = dict(regions=BAR_REGIONS, fixed=BAR_FIXED)
    with pytest.raises(ValueError, match=r"vertices: expected an array of shape \(n, 3\)"):
        softkin.scene_from_arrays(V[:, :2], E, T, **kw)
    with pytest.raises(ValueError, match=r"elements: expected .*\(#E, 4\)"):
        softkin.scene_from_arrays(V, E[:, :3], T, **kw)
    with pytest.raises(ValueError, match="tags: expected one region tag per element"):
        softkin.scene_from_arrays(V, E, T[:-1], **kw)
    bad = E.copy()
    bad[3, 1] = len(V)
    with pytest.raises(ValueError, match=r"elements\[3\]: vertex index"):
        softkin.scene_from_arrays(V, bad, T, **kw)
    with pytest.raises(ValueError, match="regions"):
        softkin.scene_from_arrays(V, E, T, regions=[{"tag": 0, "role": "rubber"}],
                                  fixed=BAR_FIXED)
    dup = np.vstack([E, E[:1]])
    with pytest.raises(ValueError, match="has the same vertices as element 0"):
        softkin.scene_from_arrays(V, dup, np.append(T, T[0]), **kw)


def test_load_scene_reads_the_thesis_mesh_and_names_missing_files(tmp_path):
    scene = softkin.load_scene(os.path.join(SOURCE_DIR, "scenes", "finger_chamber1.json"))
    assert scene.num_elements == 94240 and scene.actuators[0]["name"] == "chamber"
    with pytest.raises(ValueError, match="missing.json"):
        softkin.load_scene(str(tmp_path / "missing.json"))


def test_python_threads_solve_side_by_side_with_the_serial_answers():
    scenes = [softkin.robot("three_chamber", res=3) for _ in range(2)]
    cs = [[1.5, 1.0, 1.0], [1.0, 1.4, 1.2]]
    serial = [softkin.solve_fk(s, c, threads=1).positions for s, c in zip(scenes, cs)]
    out = [None, None]

    def run(i):
        out[i] = softkin.FkSolver(scenes[i], threads=1).solve(cs[i]).positions

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i in range(2):
        np.testing.assert_array_equal(out[i], serial[i])


def run_cli(args):
    """The softkin command: the built binary when ctest gives it (SOFTKIN_BIN), else in-process."""
    binary = os.environ.get("SOFTKIN_BIN")
    if binary:
        subprocess.run([binary] + args, check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
    else:
        assert softkin.cli(args) == 0


def vtu_points(path):
    root = ET.parse(path).getroot()
    text = root.find(".//Points/DataArray").text
    return np.array([float(t) for t in text.split()]).reshape(-1, 3)


def test_python_equals_the_command_line_bit_for_bit(finger, tmp_path):
    j, v = tmp_path / "fk.json", tmp_path / "fk.vtu"
    run_cli(["fk", "--robot", "pneumatic_finger", "--res", "5", "--actuation", "3", "--json",
             str(j), "--vtu", str(v)])
    r = softkin.FkSolver(finger).solve(3.0)
    cli = json.loads(j.read_text())
    assert cli["status"] == r.status and cli["iterations"] == r.iterations
    for name, p in r.markers.items():
        assert cli["markers"][name] == p.tolist(), name  # exact: shortest round-trip text
    np.testing.assert_array_equal(vtu_points(v), r.positions)


def test_jacobian_matches_differences_of_python_solves(finger):
    solver = softkin.FkSolver(finger, tolerance=1e-10, gradient_tolerance=1e-9)
    c, h = 2.0, 0.01
    centre = solver.solve(c)
    plus = solver.solve(c + h, warm_start=centre.positions)
    minus = solver.solve(c - h, warm_start=centre.positions)
    assert centre.converged and plus.converged and minus.converged
    fd = (plus.positions - minus.positions) / (2 * h)
    dX = solver.jacobian(c)["dX"][:, :, 0]
    assert np.abs(dX - fd).max() < 2e-3 * np.abs(fd).max()


def write_gmsh22(path, V, E, T):
    """A Gmsh 2.2 ASCII file: nodes (1-based tags, shortest round-trip text) and tets (type 4)
    with physical group = tag + 1 (Gmsh groups are positive)."""
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$Nodes", str(len(V))]
    lines += [f"{i + 1} {repr(x)} {repr(y)} {repr(z)}" for i, (x, y, z) in enumerate(V)]
    lines += ["$EndNodes", "$Elements", str(len(E))]
    lines += [f"{i + 1} 4 2 {t + 1} {t + 1} " + " ".join(str(v + 1) for v in e)
              for i, (e, t) in enumerate(zip(E, T))]
    lines += ["$EndElements"]
    path.write_text("\n".join(lines) + "\n")


def test_arrays_and_a_file_give_the_same_scene_and_answer(tmp_path):
    V, E, T = voxel_bar()
    V = V * 1.1 + 0.05  # coordinates that are not short decimals
    regions = [{"tag": 0, "role": "body", "r_omega": 1.0},
               {"tag": 1, "role": "pneumatic", "name": "chamber", "min": 1, "max": 2}]
    markers = [{"name": "tip", "box": {"min": [6.6, -1, -1], "max": [6.7, 4, 4]}}]
    fixed = [{"plane": {"point": [0.05, 0, 0], "normal": [1, 0, 0]}}]
    from_arrays = softkin.scene_from_arrays(V, E, T, regions=regions, fixed=fixed,
                                            markers=markers, name="bar")
    write_gmsh22(tmp_path / "bar.msh", V, E, T)
    file_regions = [dict(r, tag=r["tag"] + 1) for r in regions]
    (tmp_path / "bar.json").write_text(json.dumps({
        "name": "bar", "mesh": {"file": "bar.msh"}, "regions": file_regions, "fixed": fixed,
        "markers": markers}))
    from_file = softkin.load_scene(tmp_path / "bar.json")
    np.testing.assert_array_equal(from_arrays.vertices, from_file.vertices)
    np.testing.assert_array_equal(from_arrays.elements, from_file.elements)
    np.testing.assert_array_equal(from_arrays.fixed, from_file.fixed)
    a, b = softkin.solve_fk(from_arrays, 1.5), softkin.solve_fk(from_file, 1.5)
    assert a.converged and a.iterations == b.iterations
    np.testing.assert_array_equal(a.positions, b.positions)


def test_bad_input_raises_value_error_with_the_reason(finger):
    V, E, T = voxel_bar()
    kw = dict(regions=BAR_REGIONS, fixed=BAR_FIXED)
    with pytest.raises(ValueError, match="vertices: expected numbers"):
        softkin.scene_from_arrays([["a", "b", "c"]], E, T, **kw)
    with pytest.raises(ValueError, match="elements: expected integer indices"):
        softkin.scene_from_arrays(V, E + 0.5, T, **kw)
    Vn = V.copy()
    Vn[3, 1] = np.nan
    with pytest.raises(ValueError, match="NaN|non-finite|not finite"):
        softkin.scene_from_arrays(Vn, E, T, **kw)
    solver = softkin.FkSolver(finger)
    with pytest.raises(ValueError, match="expected finite numbers"):
        solver.solve(np.nan)
    with pytest.raises(ValueError, match="chamber"):
        solver.solve(50.0)  # outside [1, 10]
    with pytest.raises(ValueError, match="chamber"):
        solver.jacobian(0.5)
    with pytest.raises(ValueError, match="no_such_robot"):
        softkin.robot("no_such_robot")
    with pytest.raises(ValueError, match="options"):
        softkin.FkSolver(finger, no_such_option=1)
