#pragma once
// Tables of a study (docs/studies.md): the mean and spread over centres, the fitted convergence
// orders, and the CSV files `corrlap study` writes (results.csv, eigen.csv, summary.csv, orders.csv).
#include <string>
#include <vector>

#include "study.hpp"

namespace corrlap {

/// Mean and sample standard deviation (0 for one centre) over the centres of one
/// (study, method, normals, function, h).
struct SummaryRow {
  std::string study, method, normals, function;
  double h = 0;
  int centers = 0;
  double linf_mean = 0, linf_std = 0, l2_mean = 0, l2_std = 0;
};
/// Groups in the order they first appear in `rows`, h descending within a group.
std::vector<SummaryRow> summarize(const std::vector<StudyRow>& rows);

/// Convergence order of one (study, method, normals, function, norm): the slope of the
/// least-squares line of log(error) against log(h) through every centre's row, with the 95%
/// interval slope ± t(0.975, n - 2) * standard error of the slope. Undefined values are NaN (an
/// empty field in orders.csv): the order with fewer than two distinct h, the interval with fewer
/// than three rows, h_min and h_max without any row with a positive error.
struct OrderRow {
  std::string study, method, normals, function, norm;  ///< norm: "linf" | "l2"
  double order = 0, low = 0, high = 0;
  double h_min = 0, h_max = 0;
  int points = 0;  ///< rows with a positive error: the points of the fit
};
/// One row per group (in the order they first appear in `rows`) and norm; see OrderRow for what may
/// be undefined.
std::vector<OrderRow> fit_orders(const std::vector<StudyRow>& rows);
/// What fit_orders left undefined, one sentence per kind (orders, intervals) with a count, an
/// example and a hint; empty when every order has its interval. Front ends print them as warnings.
std::vector<std::string> order_shortfalls(const std::vector<OrderRow>& orders);
/// The text of the interval column of orders.csv.
inline constexpr const char* kOrderIntervalLabel = "95% t-interval of the least-squares slope over every centre";

/// Student's t quantile t(0.975, dof) (dof >= 1; exact table to 30, then the normal limit plus
/// the first correction term).
double student_t_975(int dof);

/// CSV files. Writers create or truncate; append_* add rows to an existing file (header written
/// when the file is new). Values with 17 significant digits; an undefined value (NaN) is an empty
/// field, never "nan" (docs/studies.md, "Undefined values").
void write_results_csv(const std::string& path, const std::vector<StudyRow>& rows, bool append);
void write_eigen_csv(const std::string& path, const std::vector<EigenRow>& rows, bool append);
void write_summary_csv(const std::string& path, const std::vector<SummaryRow>& rows);
void write_orders_csv(const std::string& path, const std::vector<OrderRow>& rows);
/// Reads what write_results_csv / write_eigen_csv wrote (resume): empty fields (and "nan" of older
/// files) are NaN. IoError naming the file and line for a malformed row or header, or an empty
/// field where every row has a value (h, centre, counts).
std::vector<StudyRow> read_results_csv(const std::string& path);
std::vector<EigenRow> read_eigen_csv(const std::string& path);

}  // namespace corrlap
