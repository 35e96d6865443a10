"""Tests of studies/plot_study.py on synthetic study directories.

Run from the repository root:  /usr/bin/python3 -m pytest tests/python -q
"""
import importlib.util
import math
import os
import subprocess

import pytest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(REPO, "studies", "plot_study.py")
PYTHON = "/usr/bin/python3"

spec = importlib.util.spec_from_file_location("plot_study", SCRIPT)
plot_study = importlib.util.module_from_spec(spec)
spec.loader.exec_module(plot_study)

SUMMARY_HEADER = ("study,method,normals,function,h,centers,"
                  "error_linf_mean,error_linf_std,error_l2_mean,error_l2_std")
ORDERS_HEADER = "study,method,normals,function,norm,order,order_low,order_high,interval,h_min,h_max"
EIGEN_HEADER = "study,method,normals,h,center,index,exact,computed,relative_error,time_s"
METHODS = {"fem": 1.0, "interpolated": 3.0}
FUNCTIONS = ["x2", "expx"]
STEPS = [0.2, 0.1, 0.05]


def write(path, header, rows):
    with open(path, "w") as f:
        f.write(header + "\n")
        for row in rows:
            f.write(",".join(str(v) for v in row) + "\n")


def summary_rows(study="backward", nan_row=False):
    rows = []
    for method, c in METHODS.items():
        for k, function in enumerate(FUNCTIONS):
            for i, h in enumerate(STEPS):
                noise = 1 + 0.05 * ((i + k) % 3 - 1)
                e = c * h ** 2 * noise
                rows.append((study, method, "true", function, h, 5, 2 * e, 0.2 * e, e, 0.1 * e))
    if nan_row:
        rows.append((study, "fem", "true", "x2", 0.025, 5, "nan", "", "NaN", "nan"))
        rows.append((study, "fem", "true", "x2", "", 5, 1e-3, 1e-4, 1e-3, 1e-4))
    return rows


def orders_rows(study="backward"):
    rows = []
    for method in METHODS:
        for function in FUNCTIONS:
            for norm in ("linf", "l2"):
                rows.append((study, method, "true", function, norm, 1.93, 1.8, 2.05, "bootstrap",
                             0.05, 0.2))
    return rows


def eigen_rows(centers=2):
    rows = []
    for method, c in METHODS.items():
        for center in range(centers):
            for index in range(49):
                l = math.isqrt(index)
                exact = l * (l + 1)
                # Index 0 (exact 0): an undefined relative error is an empty field, as corrlap writes it.
                rel = "" if index == 0 else -c * 1e-4 * (1 + l) ** 2 * (1 + 0.1 * center)
                computed = 1e-12 if index == 0 else exact * (1 + rel)
                rows.append(("eigen", method, "true", 0.05, center, index, exact, computed, rel,
                             0.1))
    return rows


def make_study(directory):
    write(directory / "summary.csv", SUMMARY_HEADER, summary_rows())
    write(directory / "orders.csv", ORDERS_HEADER, orders_rows())
    write(directory / "eigen.csv", EIGEN_HEADER, eigen_rows())
    return directory


@pytest.fixture
def study_dir(tmp_path):
    return make_study(tmp_path)


@pytest.fixture(scope="module")
def plotted(tmp_path_factory):
    """A full study plotted once (in process): (directory, returned paths)."""
    directory = make_study(tmp_path_factory.mktemp("study"))
    return directory, plot_study.plot_study(str(directory))


def run_cli(*args, env=None):
    return subprocess.run([PYTHON, SCRIPT, *map(str, args)], capture_output=True, text=True,
                          env=env, timeout=60)


def check_png_svg(stem):
    png, svg = stem.parent / (stem.name + ".png"), stem.parent / (stem.name + ".svg")
    assert png.is_file() and png.stat().st_size > 0, png
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert svg.is_file() and svg.stat().st_size > 0, svg
    text = svg.read_text()
    assert "<svg" in text
    return text


def test_writes_all_figures(plotted):
    study_dir, paths = plotted
    plots = study_dir / "plots"
    expected = []
    for function in FUNCTIONS:
        for norm in ("linf", "l2"):
            expected.append(plots / f"backward_true_{function}_{norm}")
    expected.append(plots / "eigen_true_h0.05")
    for stem in expected:
        check_png_svg(stem)
    assert sorted(paths) == sorted(str(s) + ext for s in expected for ext in (".png", ".svg"))


def test_svg_text_has_orders_title_and_reference(plotted):
    study_dir, _ = plotted
    text = check_png_svg(study_dir / "plots" / "backward_true_x2_l2")
    assert "fem (order 1.93)" in text
    assert "interpolated (order 1.93)" in text
    assert "h^2" in text
    assert "backward, true normals, x2 \u2014 L2" in text
    assert "grid step h" in text and "L2 error (M-weighted)" in text
    eigen = check_png_svg(study_dir / "plots" / "eigen_true_h0.05")
    assert "eigenvalues, true normals, h = 0.05" in eigen
    assert "fem" in eigen and "interpolated" in eigen
    for svg in (text, eigen):  # the fixed colours of fem and interpolated, in every figure
        assert "#1f77b4" in svg and "#ff7f0e" in svg


def test_forward_and_cotan_use_slope_one_and_no_orders(tmp_path):
    write(tmp_path / "summary.csv", SUMMARY_HEADER,
          summary_rows("forward") + summary_rows("cotan"))
    paths = plot_study.plot_study(str(tmp_path), formats=("svg",))
    assert len(paths) == 2 * 2 * 2  # studies x functions x norms
    text = (tmp_path / "plots" / "cotan_true_expx_linf.svg").read_text()
    assert "h^1" in text and "L\u221e error" in text and "order" not in text
    assert (tmp_path / "plots" / "forward_true_x2_l2.svg").is_file()


def test_cli_prints_paths_and_formats(tmp_path):
    write(tmp_path / "eigen.csv", EIGEN_HEADER, eigen_rows())
    result = run_cli(tmp_path, "--formats", "png")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == [str(tmp_path / "plots" / "eigen_true_h0.05.png")]
    assert not (tmp_path / "plots" / "eigen_true_h0.05.svg").exists()


def test_nan_and_empty_values_are_skipped(tmp_path):
    write(tmp_path / "summary.csv", SUMMARY_HEADER, summary_rows(nan_row=True))
    rows = eigen_rows(centers=1)
    rows[5] = rows[5][:8] + ("",) + rows[5][9:]
    write(tmp_path / "eigen.csv", EIGEN_HEADER, rows)
    paths = plot_study.plot_study(str(tmp_path))
    assert len(paths) == 2 * 5
    check_png_svg(tmp_path / "plots" / "backward_true_x2_l2")
    check_png_svg(tmp_path / "plots" / "eigen_true_h0.05")


def test_empty_orders_leave_the_legend_without_an_order(tmp_path):
    """orders.csv as corrlap writes it with one grid step: the order and interval fields empty."""
    write(tmp_path / "summary.csv", SUMMARY_HEADER, summary_rows())
    rows = orders_rows()
    rows[0] = rows[0][:5] + ("", "", "") + rows[0][8:]  # fem x2 linf
    write(tmp_path / "orders.csv", ORDERS_HEADER, rows)
    plot_study.plot_study(str(tmp_path), formats=("svg",))
    linf = (tmp_path / "plots" / "backward_true_x2_linf.svg").read_text()
    assert "fem (order" not in linf and "interpolated (order 1.93)" in linf
    assert "fem (order 1.93)" in (tmp_path / "plots" / "backward_true_x2_l2.svg").read_text()


def test_missing_column_is_exit_1_naming_it(tmp_path):
    header = SUMMARY_HEADER.replace(",error_l2_mean", "")
    write(tmp_path / "summary.csv", header, [row[:8] + row[9:] for row in summary_rows()])
    result = run_cli(tmp_path)
    assert result.returncode == 1
    summary = os.path.join(str(tmp_path), "summary.csv")
    assert f"plot_study: {summary}: missing column 'error_l2_mean'" in result.stderr
    assert not (tmp_path / "plots").exists()


def test_garbage_number_is_exit_1(tmp_path, capsys):
    rows = summary_rows()
    rows[0] = rows[0][:4] + ("abc",) + rows[0][5:]
    write(tmp_path / "summary.csv", SUMMARY_HEADER, rows)
    assert plot_study.main([str(tmp_path)]) == 1
    assert "summary.csv:2: column 'h': not a number 'abc'" in capsys.readouterr().err
    assert not (tmp_path / "plots").exists()  # checked before anything is written


def test_empty_directory_is_exit_1(tmp_path, capsys):
    assert plot_study.main([str(tmp_path)]) == 1
    assert f"plot_study: no summary.csv, eigen.csv or regularization.csv in {tmp_path}" in capsys.readouterr().err
    assert plot_study.main([str(tmp_path / "absent")]) == 1
    assert "not a directory" in capsys.readouterr().err


REGULARIZATION_HEADER = ("study,shape,method,normals,h,resolution,vertices,faces,distance_before,distance_after,"
                         "angle_before,angle_after,curvature_error_before,curvature_error_after,area_before,"
                         "area_after,time_s")


def test_regularization_study_figures(tmp_path):
    """One distance and one curvature figure per shape (paper Fig. 15); a zero error is left out."""
    rows = []
    for shape in ("sphere1", "torus"):
        for h in STEPS:
            for method, c in (("fem", 0.1), ("polydec", 0.2), ("alignment", 0.0)):
                rows.append(("regularization", shape, method, "ii", h, 0, 100, 100, h / 4, c * h ** 1.5,
                             17.0, 1.0, 0.5, c * h, 18.0, 12.6, 0.1))
    write(tmp_path / "regularization.csv", REGULARIZATION_HEADER, rows)
    paths = plot_study.plot_study(str(tmp_path), formats=("png",))
    names = sorted(os.path.basename(p) for p in paths)
    assert names == ["regularization_sphere1_curvature.png", "regularization_sphere1_distance.png",
                     "regularization_torus_curvature.png", "regularization_torus_distance.png"]
    assert all(os.path.getsize(p) > 1000 for p in paths)


SWEEP_HEADER = ("study,shape,method,normals,h,resolution,alpha0,vertices,faces,distance_before,distance_after,"
                "angle_before,angle_after,curvature_error_before,curvature_error_after,area_before,area_after,"
                "volume_before,volume_after,time_s")


def test_alpha0_sweep_figures(tmp_path):
    """An alpha0 sweep (paper Fig. 13): against h once per alpha0, against alpha0 once per h and
    quantity; the baseline (empty alpha0) is a flat line, not a point."""
    rows = []
    for h in (0.2, 0.1):
        for alpha0 in (0.01, 1, 100):
            for method, c in (("fem", 1.0), ("polydec", 1.0 + 1 / alpha0)):
                rows.append(("regularization", "sphere1", method, "ii", h, 0, alpha0, 100, 100, h / 4, c * h ** 2,
                             17.0, c, 0.5, c * h, 18.0, 12.6 * c, 4.0, 4.2 * c, 0.1))
        rows.append(("regularization", "sphere1", "alignment", "ii", h, 0, "", 100, 100, h / 4, h / 8,
                     17.0, 2.0, 0.5, h, 18.0, 12.3, 4.0, 4.1, 0.1))
    write(tmp_path / "regularization.csv", SWEEP_HEADER, rows)
    paths = plot_study.plot_study(str(tmp_path), formats=("png",))
    names = sorted(os.path.basename(p) for p in paths)
    against_h = [f"regularization_sphere1_{q}_alpha0_{a}.png" for a in ("0.01", "1", "100")
                 for q in ("curvature", "distance")]
    against_alpha0 = [f"alpha0_sphere1_h{h}_{q}.png" for h in ("0.1", "0.2")
                      for q in ("angle", "area", "curvature", "distance", "volume")]
    assert names == sorted(against_h + against_alpha0)
    assert all(os.path.getsize(p) > 1000 for p in paths)


def test_header_only_is_exit_1(tmp_path, capsys):
    write(tmp_path / "summary.csv", SUMMARY_HEADER, [])
    assert plot_study.main([str(tmp_path)]) == 1
    assert "nothing to plot" in capsys.readouterr().err


def test_missing_matplotlib_is_exit_3(study_dir, tmp_path):
    fake = tmp_path / "fake_site" / "matplotlib"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise ImportError('matplotlib hidden by the test')\n")
    env = dict(os.environ, PYTHONPATH=str(fake.parent))
    result = run_cli(study_dir, env=env)
    assert result.returncode == 3
    assert ("plot_study: matplotlib not available (apt-get install python3-matplotlib); "
            "plots skipped") in result.stderr
