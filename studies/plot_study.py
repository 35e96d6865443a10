#!/usr/bin/python3
"""plot_study.py DIR [--formats png,svg]: figures of a `corrlap study ... --out DIR` run.

Inputs (comma-separated, header first, unknown extra columns ignored, a file may be absent):
  DIR/summary.csv  study,method,normals,function,h,centers,
                   error_linf_mean,error_linf_std,error_l2_mean,error_l2_std
                   (study forward, backward or cotan; other studies are ignored)
  DIR/orders.csv   study,method,normals,function,norm,order,...   (optional; legend labels)
  DIR/eigen.csv    study,method,normals,h,center,index,exact,computed,relative_error,time_s
  DIR/regularization.csv  study,shape,method,normals,h,alpha0,distance_*,angle_*,curvature_error_*,
                   area_*,volume_* (each *_before and *_after)
DIR/results.csv (one row per centre) is not read: summary.csv already holds its means.

Outputs, in DIR/plots/, each in every requested format (default png at dpi 150 and svg):
  <study>_<normals>_<function>_<norm>.<ext>   log-log error against h, one line per method,
                                              band mean +- std, reference slope (h^2 backward,
                                              h^1 forward and cotan); norm is linf or l2
  eigen_<normals>_h<h>.<ext>                  |relative error| of eigenvalues 1.. (mean over
                                              centres), one line per method, multiplets marked
  regularization_<shape>_<quantity>[_alpha0_<a>].<ext>
                                              distance or |H| error against h, one line per
                                              method, the staircase dashed (per alpha0 when the
                                              study swept several)
  alpha0_<shape>_h<h>_<quantity>.<ext>        distance, normal angle, |H| error, area or volume
                                              against alpha0, when two or more were swept
Empty values are undefined and skipped (corrlap writes an empty field, never nan: docs/studies.md,
"Undefined values"; the nan of older files reads the same). The written paths are printed one per
line on stdout.

Exit codes: 0 success; 1 malformed or missing input (message on stderr); 2 bad command line;
3 matplotlib not available (plots skipped).

Only Debian's /usr/bin/python3 with python3-matplotlib and python3-numpy is needed.
"""
import argparse
import csv
import math
import os
import re
import sys

try:  # matplotlib needs numpy: either missing means the plots are skipped (exit code 3)
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams["svg.fonttype"] = "none"  # SVG text stays text (searchable)
    plt.rcParams["svg.hashsalt"] = "corrlap"  # stable element ids
except ImportError:
    plt = None

CONVERGENCE_STUDIES = ("forward", "backward", "cotan")
NORMS = {"linf": "L\u221e", "l2": "L2"}
Y_LABELS = {"linf": "L\u221e error", "l2": "L2 error (M-weighted)"}
REFERENCE_SLOPE = {"forward": 1, "backward": 2, "cotan": 1}
METHOD_COLORS = {
    "fem": "#1f77b4",
    "interpolated": "#ff7f0e",
    "corrected-vrm": "#2ca02c",
    "projected-polydec": "#d62728",
    "polydec": "#9467bd",
    "heat-kernel": "#8c564b",
    "vrm": "#e377c2",
    "cotan": "#7f7f7f",
    "alignment": "#17becf",
}
FALLBACK_COLORS = ["#bcbd22", "#17becf", "#000000", "#aec7e8", "#ffbb78", "#98df8a", "#ff9896"]
# Columns read from each file: (text columns, numeric columns); others are ignored.
SUMMARY_COLUMNS = (["study", "method", "normals", "function"],
                   ["h", "error_linf_mean", "error_linf_std", "error_l2_mean", "error_l2_std"])
ORDERS_COLUMNS = (["study", "method", "normals", "function", "norm"], ["order"])
EIGEN_COLUMNS = (["method", "normals"], ["h", "index", "relative_error"])
# A third list names numeric columns that may be absent (NaN then): files of older versions.
REGULARIZATION_COLUMNS = (["shape", "method", "normals"],
                          ["h", "distance_before", "distance_after", "curvature_error_before",
                           "curvature_error_after", "area_before", "area_after"],
                          ["alpha0", "angle_before", "angle_after", "volume_before", "volume_after"])
# The regularization study's figures against h (paper Fig. 15): quantity -> (before column, after
# column, label).
REGULARIZATION_QUANTITIES = {
    "distance": ("distance_before", "distance_after", "mean distance to the true surface"),
    "curvature": ("curvature_error_before", "curvature_error_after", "mean |H - H_true|"),
}
# Against alpha0 (paper Fig. 13): quantity -> (before column, after column, label, log y).
ALPHA0_QUANTITIES = {
    "distance": ("distance_before", "distance_after", "mean distance to the true surface", True),
    "angle": ("angle_before", "angle_after", "mean normal angle (degrees)", True),
    "curvature": ("curvature_error_before", "curvature_error_after", "mean |H - H_true|", True),
    "area": ("area_before", "area_after", "area", False),
    "volume": ("volume_before", "volume_after", "enclosed volume", False),
}


class InputError(Exception):
    """Malformed or missing input; the message names the file (exit code 1)."""


class MatplotlibMissing(Exception):
    """matplotlib cannot be imported (exit code 3)."""


def read_table(path, columns):
    """Rows of a CSV file as dicts (numeric columns as floats), or None if the file is absent.

    Every numeric value is checked here, before anything is plotted: empty or NaN gives NaN,
    anything else that is not a number is an InputError naming the file, line and column.
    """
    if not os.path.isfile(path):
        return None
    text_columns, number_columns = columns[0], columns[1]
    optional_columns = columns[2] if len(columns) > 2 else []
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        if reader.fieldnames is None:
            raise InputError(f"{path}: empty file (no header line)")
        reader.fieldnames = [name.strip() for name in reader.fieldnames]
        for column in text_columns + number_columns:
            if column not in reader.fieldnames:
                raise InputError(f"{path}: missing column '{column}'")
        rows = []
        for raw in reader:
            row = {column: (raw[column] or "").strip() for column in text_columns}
            for column in number_columns:
                row[column] = number(raw[column], f"{path}:{reader.line_num}", column)
            for column in optional_columns:
                row[column] = number(raw.get(column), f"{path}:{reader.line_num}", column)
            rows.append(row)
        return rows


def number(text, where, column):
    """A CSV value as a float: empty or NaN gives NaN; anything else not a number is an error."""
    text = (text or "").strip()
    if text == "":
        return math.nan
    try:
        return float(text)
    except ValueError:
        raise InputError(f"{where}: column '{column}': not a number '{text}'") from None


def positive(x):
    return math.isfinite(x) and x > 0


def safe_name(text):
    """A file-name fragment: characters other than letters, digits, '.', '-' become '_'."""
    return re.sub(r"[^A-Za-z0-9.\-]", "_", text) or "_"


def method_colors(methods):
    """Fixed colour for the known methods; unknown ones take the fallback cycle in sorted order."""
    colors = {}
    unknown = sorted(m for m in set(methods) if m not in METHOD_COLORS)
    for i, method in enumerate(unknown):
        colors[method] = FALLBACK_COLORS[i % len(FALLBACK_COLORS)]
    colors.update(METHOD_COLORS)
    return colors


def save(fig, directory, stem, formats):
    """Saves fig as DIR/plots/<stem>.<ext> for every format; returns the paths."""
    os.makedirs(os.path.join(directory, "plots"), exist_ok=True)
    paths = []
    for ext in formats:
        path = os.path.join(directory, "plots", f"{stem}.{ext}")
        metadata = {"Date": None} if ext == "svg" else None
        fig.savefig(path, dpi=150, metadata=metadata)
        paths.append(path)
    plt.close(fig)
    return paths


def order_table(rows):
    """(study, method, normals, function, norm) -> fitted order, for the legend."""
    orders = {}
    for row in rows or []:
        order = row["order"]
        if math.isfinite(order):
            key = (row["study"], row["method"], row["normals"], row["function"], row["norm"])
            orders[key] = order
    return orders


def convergence_series(rows, norm):
    """method -> (h, mean, std) arrays sorted by h, keeping rows with positive h and mean."""
    points = {}
    for row in rows:
        h, mean, std = row["h"], row[f"error_{norm}_mean"], row[f"error_{norm}_std"]
        if positive(h) and positive(mean):
            std = std if math.isfinite(std) else 0.0
            points.setdefault(row["method"], []).append((h, mean, std))
    series = {}
    for method, values in points.items():
        values.sort()
        series[method] = tuple(np.array(column) for column in zip(*values))
    return series


def draw_reference_slope(ax, series, slope):
    """Dashed grey line of the given slope over the h range, below the data at the largest h."""
    h_all = np.concatenate([h for h, _, _ in series.values()])
    h_min, h_max = h_all.min(), h_all.max()
    if h_min == h_max:
        return
    y_at_max = min(mean[np.argmax(h)] for h, mean, _ in series.values())
    h_line = np.array([h_min, h_max])
    y_line = 0.5 * y_at_max * (h_line / h_max) ** slope
    ax.plot(h_line, y_line, linestyle="--", color="grey", linewidth=1, label=f"h^{slope}")


def plot_convergence(rows, key, norm, orders, colors):
    """One log-log figure of error against h for (study, normals, function) and a norm, or None."""
    study, normals, function = key
    series = convergence_series(rows, norm)
    if not series:
        return None
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for method in sorted(series):
        h, mean, std = series[method]
        order = orders.get((study, method, normals, function, norm))
        label = method if order is None else f"{method} (order {order:.2f})"
        color = colors[method]
        ax.plot(h, mean, marker="o", color=color, label=label)
        lower = np.where(mean - std > 0, mean - std, 0.1 * mean)  # log axis: keep it positive
        ax.fill_between(h, lower, mean + std, color=color, alpha=0.15, linewidth=0)
    draw_reference_slope(ax, series, REFERENCE_SLOPE[study])
    ax.set_xscale("log")
    ax.set_yscale("log")
    # The cotan study's mesh is scaled so that its longest side spans 2: N voxels mean h = 2 / N.
    ax.set_xlabel("grid step h = 2 / resolution" if study == "cotan" else "grid step h")
    ax.set_ylabel(Y_LABELS[norm])
    ax.set_title(f"{study}, {normals} normals, {function} \u2014 {NORMS[norm]}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig


def plot_convergence_studies(directory, summary, orders, colors, formats):
    groups = {}
    for row in summary:
        if row["study"] in CONVERGENCE_STUDIES:
            groups.setdefault((row["study"], row["normals"], row["function"]), []).append(row)
    paths = []
    for key in sorted(groups):
        for norm in NORMS:
            fig = plot_convergence(groups[key], key, norm, orders, colors)
            if fig is not None:
                stem = "_".join(safe_name(part) for part in (*key, norm))
                paths += save(fig, directory, stem, formats)
    return paths


def eigen_series(rows):
    """method -> (index, mean |relative error| over centres), indices >= 1 with a positive error."""
    errors = {}
    for row in rows:
        index, error = row["index"], abs(row["relative_error"])
        if math.isfinite(index) and index >= 1 and math.isfinite(error):
            errors.setdefault(row["method"], {}).setdefault(int(index), []).append(error)
    series = {}
    for method, by_index in errors.items():
        indices = sorted(i for i in by_index if np.mean(by_index[i]) > 0)
        if indices:
            series[method] = (np.array(indices), np.array([np.mean(by_index[i]) for i in indices]))
    return series


def plot_eigen(rows, normals, h, colors):
    """One figure of |relative error| against eigenvalue index (the paper's Fig. 9), or None."""
    series = eigen_series(rows)
    if not series:
        return None
    fig, ax = plt.subplots(figsize=(7, 4.5))
    last = max(index.max() for index, _ in series.values())
    for l in range(1, math.isqrt(int(last)) + 1):  # multiplet l spans indices l^2 .. (l+1)^2-1
        ax.axvline(l * l, color="lightgrey", linewidth=0.8, zorder=0)
    for method in sorted(series):
        index, error = series[method]
        ax.plot(index, error, marker=".", color=colors[method], label=method)
    ax.set_yscale("log")
    ax.set_xlabel("eigenvalue index")
    ax.set_ylabel("|relative error|")
    ax.set_title(f"eigenvalues, {normals} normals, h = {h:g}")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig


def plot_eigen_study(directory, eigen, colors, formats):
    groups = {}
    for row in eigen:
        h = row["h"]
        if positive(h):
            groups.setdefault((row["normals"], h), []).append(row)
    paths = []
    for normals, h in sorted(groups):
        fig = plot_eigen(groups[(normals, h)], normals, h, colors)
        if fig is not None:
            paths += save(fig, directory, f"eigen_{safe_name(normals)}_h{h:g}", formats)
    return paths


def plot_regularization(rows, title, quantity, colors):
    """One log-log figure of a quality against h for one shape: one line per method after the
    regularization, the staircase (before) dashed; None when nothing is positive."""
    before_column, after_column, label = REGULARIZATION_QUANTITIES[quantity]
    by_method = {}
    staircase = {}
    for row in rows:
        h = row["h"]
        if not positive(h):
            continue
        if positive(row[after_column]):
            by_method.setdefault(row["method"], []).append((h, row[after_column]))
        if positive(row[before_column]):
            staircase[h] = row[before_column]
    if not by_method:
        return None
    fig, ax = plt.subplots(figsize=(6, 4.5))
    if staircase:
        hs = sorted(staircase)
        ax.plot(hs, [staircase[h] for h in hs], linestyle="--", marker="s", color="grey", label="digital surface")
    for method in sorted(by_method):
        points = sorted(by_method[method])
        ax.plot([p[0] for p in points], [p[1] for p in points], marker="o", color=colors[method], label=method)
    ax.set_yscale("log")
    return finish_axes(fig, ax, "grid step h", label, f"regularization, {title}: {label}")


def finish_axes(fig, ax, xlabel, ylabel, title):
    """The regularization figures' common ending: log x, labels, title, grid, legend."""
    ax.set_xscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig


def plot_alpha0(rows, title, quantity, colors):
    """One figure of a quality against alpha0 (log x) for one shape and h: one line per method,
    the staircase dashed, and dotted horizontal lines for what has no place on a log axis: the
    baseline (no alpha0) and any method at alpha0 = 0; None when no method has two values."""
    before_column, after_column, label, log_y = ALPHA0_QUANTITIES[quantity]
    usable = (lambda v: positive(v)) if log_y else (lambda v: math.isfinite(v))
    by_method, flat = {}, {}
    staircase = None
    for row in rows:
        if usable(row[before_column]):
            staircase = row[before_column]
        if not usable(row[after_column]):
            continue
        if positive(row["alpha0"]):
            by_method.setdefault(row["method"], []).append((row["alpha0"], row[after_column]))
        elif math.isfinite(row["alpha0"]):
            flat[f"{row['method']}, alpha0 = 0"] = (row["method"], row[after_column])
        else:
            flat[f"{row['method']} (no alpha0)"] = (row["method"], row[after_column])
    by_method = {m: sorted(points) for m, points in by_method.items() if len(points) >= 2}
    if not by_method:
        return None
    fig, ax = plt.subplots(figsize=(6, 4.5))
    if staircase is not None:
        ax.axhline(staircase, linestyle="--", color="grey", label="digital surface")
    for label_text in sorted(flat):
        method, value = flat[label_text]
        ax.axhline(value, linestyle=":", color=colors[method], label=label_text)
    for method in sorted(by_method):
        points = by_method[method]
        ax.plot([p[0] for p in points], [p[1] for p in points], marker="o", color=colors[method], label=method)
    if log_y:
        ax.set_yscale("log")
    return finish_axes(fig, ax, "attachment weight alpha0", label, f"regularization, {title}: {label}")


def plot_regularization_study(directory, rows, colors, formats):
    """Against h, per shape (and per alpha0 when several, the baseline in each); against alpha0,
    per shape and h when the study swept two or more."""
    shapes = {}
    for row in rows:
        shapes.setdefault(row["shape"], []).append(row)
    paths = []
    for shape in sorted(shapes):
        shape_rows = shapes[shape]
        weights = sorted({row["alpha0"] for row in shape_rows if math.isfinite(row["alpha0"])})
        for alpha0 in weights if len(weights) > 1 else [None]:
            selected = [row for row in shape_rows
                        if alpha0 is None or not math.isfinite(row["alpha0"]) or row["alpha0"] == alpha0]
            title = shape if alpha0 is None else f"{shape}, alpha0 = {alpha0:g}"
            suffix = "" if alpha0 is None else f"_alpha0_{alpha0:g}"
            for quantity in REGULARIZATION_QUANTITIES:
                fig = plot_regularization(selected, title, quantity, colors)
                if fig is not None:
                    paths += save(fig, directory, f"regularization_{safe_name(shape)}_{quantity}{suffix}", formats)
        if len([a for a in weights if a > 0]) < 2:
            continue
        for h in sorted({row["h"] for row in shape_rows if positive(row["h"])}):
            selected = [row for row in shape_rows if row["h"] == h]
            for quantity in ALPHA0_QUANTITIES:
                fig = plot_alpha0(selected, f"{shape}, h = {h:g}", quantity, colors)
                if fig is not None:
                    paths += save(fig, directory, f"alpha0_{safe_name(shape)}_h{h:g}_{quantity}", formats)
    return paths


def plot_study(directory, formats=("png", "svg")):
    """Writes the figures of a study directory into DIR/plots/; returns the written paths."""
    if plt is None:
        raise MatplotlibMissing("matplotlib not available (apt-get install python3-matplotlib); "
                                "plots skipped")
    if not os.path.isdir(directory):
        raise InputError(f"{directory}: not a directory")
    summary = read_table(os.path.join(directory, "summary.csv"), SUMMARY_COLUMNS)
    eigen = read_table(os.path.join(directory, "eigen.csv"), EIGEN_COLUMNS)
    regularization = read_table(os.path.join(directory, "regularization.csv"), REGULARIZATION_COLUMNS)
    if summary is None and eigen is None and regularization is None:
        raise InputError(f"no summary.csv, eigen.csv or regularization.csv in {directory}")
    orders = order_table(read_table(os.path.join(directory, "orders.csv"), ORDERS_COLUMNS))
    colors = method_colors(row["method"] for row in (summary or []) + (eigen or []) + (regularization or []))
    paths = []
    if regularization is not None:
        paths += plot_regularization_study(directory, regularization, colors, formats)
    if summary is not None:
        paths += plot_convergence_studies(directory, summary, orders, colors, formats)
    if eigen is not None:
        paths += plot_eigen_study(directory, eigen, colors, formats)
    if not paths:
        raise InputError(f"nothing to plot in {directory}: no row with a finite positive error")
    return paths


def main(argv=None):
    parser = argparse.ArgumentParser(prog="plot_study", description=__doc__.splitlines()[0])
    parser.add_argument("directory", help="output directory of `corrlap study ... --out DIR`")
    parser.add_argument("--formats", default="png,svg", help="comma-separated (png, svg, pdf)")
    args = parser.parse_args(argv)
    formats = [ext.strip() for ext in args.formats.split(",") if ext.strip()]
    if not formats or any(ext not in ("png", "svg", "pdf") for ext in formats):
        parser.error(f"--formats {args.formats}: expected a list of png, svg, pdf")
    try:
        paths = plot_study(args.directory, formats)
    except MatplotlibMissing as e:
        print(f"plot_study: {e}", file=sys.stderr)
        return 3
    except (InputError, OSError) as e:
        print(f"plot_study: {e}", file=sys.stderr)
        return 1
    for path in paths:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
