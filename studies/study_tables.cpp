#include "study_tables.hpp"

#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "detail/csv.hpp"

namespace corrlap {

using detail::close_csv;
using detail::CsvReader;
using detail::kNaN;
using detail::number;
using detail::open_csv;

namespace {
constexpr const char* kResultsHeader =
    "study,method,normals,function,h,center,cx,cy,cz,vertices,faces,error_linf,error_l2,time_s";
constexpr const char* kEigenHeader = "study,method,normals,h,center,index,exact,computed,relative_error,time_s";

struct MeanStd {
  double mean = 0, std = 0;
};
MeanStd mean_std(const std::vector<double>& v) {
  MeanStd r;
  if (v.empty()) return r;
  for (double x : v) r.mean += x;
  r.mean /= double(v.size());
  if (v.size() > 1) {
    double ss = 0;
    for (double x : v) ss += (x - r.mean) * (x - r.mean);
    r.std = std::sqrt(ss / double(v.size() - 1));
  }
  return r;
}

// The rows of each (study, method, normals, function), groups in the order they first appear.
std::vector<std::vector<const StudyRow*>> group_rows(const std::vector<StudyRow>& rows) {
  std::map<std::string, std::size_t> index;
  std::vector<std::vector<const StudyRow*>> groups;
  for (const StudyRow& r : rows) {
    const std::string key = r.study + '\n' + r.method + '\n' + r.normals + '\n' + r.function;
    const auto [it, fresh] = index.emplace(key, groups.size());
    if (fresh) groups.emplace_back();
    groups[it->second].push_back(&r);
  }
  return groups;
}

// The labels of a group's first row onto a table row (SummaryRow, OrderRow).
template <class TableRow>
void copy_labels(const StudyRow& from, TableRow& to) {
  to.study = from.study;
  to.method = from.method;
  to.normals = from.normals;
  to.function = from.function;
}

}  // namespace

std::vector<SummaryRow> summarize(const std::vector<StudyRow>& rows) {
  std::vector<SummaryRow> out;
  for (const auto& group : group_rows(rows)) {
    std::map<double, std::vector<const StudyRow*>, std::greater<>> by_h;
    for (const StudyRow* r : group) by_h[r->h].push_back(r);
    for (const auto& [h, members] : by_h) {
      SummaryRow s;
      copy_labels(*members.front(), s);
      s.h = h;
      s.centers = int(members.size());
      std::vector<double> linf, l2;
      for (const StudyRow* m : members) {
        linf.push_back(m->error_linf);
        l2.push_back(m->error_l2);
      }
      const MeanStd a = mean_std(linf), b = mean_std(l2);
      s.linf_mean = a.mean;
      s.linf_std = a.std;
      s.l2_mean = b.mean;
      s.l2_std = b.std;
      out.push_back(s);
    }
  }
  return out;
}

double student_t_975(int dof) {
  static const double table[31] = {0,     12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
                                   2.201, 2.179,  2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080,
                                   2.074, 2.069,  2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
  if (dof < 1) return kNaN;
  if (dof <= 30) return table[dof];
  const double z = 1.959964;  // Cornish-Fisher: z + (z^3 + z) / (4 dof)
  return z + (z * z * z + z) / (4.0 * double(dof));
}

std::vector<OrderRow> fit_orders(const std::vector<StudyRow>& rows) {
  std::vector<OrderRow> out;
  for (const auto& g : group_rows(rows))
    for (const char* norm : {"linf", "l2"}) {
      std::vector<double> x, y;
      double h_min = std::numeric_limits<double>::infinity(), h_max = 0;
      for (const StudyRow* r : g) {
        const double e = std::string(norm) == "linf" ? r->error_linf : r->error_l2;
        if (!(e > 0) || !std::isfinite(e)) continue;  // log of a zero error: not a point of the fit
        x.push_back(std::log(r->h));
        y.push_back(std::log(e));
        h_min = std::min(h_min, r->h);
        h_max = std::max(h_max, r->h);
      }
      OrderRow o;
      copy_labels(*g.front(), o);
      o.norm = norm;
      o.points = int(x.size());
      o.order = o.low = o.high = kNaN;
      o.h_min = x.empty() ? kNaN : h_min;
      o.h_max = x.empty() ? kNaN : h_max;
      // A slope needs two distinct h: the group stays in the table with its order undefined, so
      // that the table and the warning (order_shortfalls) say what is missing.
      if (x.size() < 2 || !(h_min < h_max)) {
        out.push_back(o);
        continue;
      }
      const double n = double(x.size());
      double mx = 0, my = 0;
      for (std::size_t i = 0; i < x.size(); ++i) mx += x[i], my += y[i];
      mx /= n;
      my /= n;
      double sxx = 0, sxy = 0;
      for (std::size_t i = 0; i < x.size(); ++i) sxx += (x[i] - mx) * (x[i] - mx), sxy += (x[i] - mx) * (y[i] - my);
      o.order = sxy / sxx;
      if (x.size() >= 3) {
        double ssr = 0;
        for (std::size_t i = 0; i < x.size(); ++i) {
          const double fit = my + o.order * (x[i] - mx);
          ssr += (y[i] - fit) * (y[i] - fit);
        }
        const double se = std::sqrt(ssr / (n - 2.0) / sxx);
        const double t = student_t_975(int(x.size()) - 2);
        o.low = o.order - t * se;
        o.high = o.order + t * se;
      }
      out.push_back(o);
    }
  return out;
}

std::vector<std::string> order_shortfalls(const std::vector<OrderRow>& orders) {
  const auto label = [](const OrderRow& r) {
    return r.study + " " + r.method + " " + r.normals + " " + r.function + " " + (r.norm == "l2" ? "L2" : "Linf") +
           ", " + std::to_string(r.points) + " row(s)";
  };
  int no_order = 0, no_interval = 0;
  const OrderRow *first_order = nullptr, *first_interval = nullptr;
  for (const OrderRow& r : orders) {
    if (std::isnan(r.order)) {
      if (no_order++ == 0) first_order = &r;
    } else if (std::isnan(r.low)) {
      if (no_interval++ == 0) first_interval = &r;
    }
  }
  std::vector<std::string> out;
  if (no_order > 0)
    out.push_back(std::to_string(no_order) + " order(s) left empty (e.g. " + label(*first_order) +
                  "): a slope needs rows at two grid steps h or more with a positive error; give more grid steps");
  if (no_interval > 0)
    out.push_back(std::to_string(no_interval) + " interval(s) left empty (e.g. " + label(*first_interval) +
                  "): the t-interval needs three rows or more; give a third grid step or more centres");
  return out;
}

void write_results_csv(const std::string& path, const std::vector<StudyRow>& rows, bool append) {
  std::FILE* f = open_csv(path, append, kResultsHeader);
  for (const StudyRow& r : rows)
    std::fprintf(f, "%s,%s,%s,%s,%s,%d,%s,%s,%s,%lld,%lld,%s,%s,%s\n", r.study.c_str(), r.method.c_str(),
                 r.normals.c_str(), r.function.c_str(), number(r.h).c_str(), r.center, number(r.c.x()).c_str(),
                 number(r.c.y()).c_str(), number(r.c.z()).c_str(), r.vertices, r.faces, number(r.error_linf).c_str(),
                 number(r.error_l2).c_str(), number(r.time_s).c_str());
  close_csv(f, path);
}

void write_eigen_csv(const std::string& path, const std::vector<EigenRow>& rows, bool append) {
  std::FILE* f = open_csv(path, append, kEigenHeader);
  for (const EigenRow& r : rows)
    std::fprintf(f, "eigen,%s,%s,%s,%d,%d,%s,%s,%s,%s\n", r.method.c_str(), r.normals.c_str(), number(r.h).c_str(),
                 r.center, r.index, number(r.exact).c_str(), number(r.computed).c_str(),
                 number(r.relative_error).c_str(), number(r.time_s).c_str());
  close_csv(f, path);
}

void write_summary_csv(const std::string& path, const std::vector<SummaryRow>& rows) {
  std::FILE* f = open_csv(path, false,
                          "study,method,normals,function,h,centers,error_linf_mean,error_linf_std,error_l2_mean,"
                          "error_l2_std");
  for (const SummaryRow& r : rows)
    std::fprintf(f, "%s,%s,%s,%s,%s,%d,%s,%s,%s,%s\n", r.study.c_str(), r.method.c_str(), r.normals.c_str(),
                 r.function.c_str(), number(r.h).c_str(), r.centers, number(r.linf_mean).c_str(),
                 number(r.linf_std).c_str(), number(r.l2_mean).c_str(), number(r.l2_std).c_str());
  close_csv(f, path);
}

void write_orders_csv(const std::string& path, const std::vector<OrderRow>& rows) {
  std::FILE* f = open_csv(path, false,
                          "study,method,normals,function,norm,order,order_low,order_high,interval,h_min,h_max,points");
  for (const OrderRow& r : rows)
    std::fprintf(f, "%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%d\n", r.study.c_str(), r.method.c_str(), r.normals.c_str(),
                 r.function.c_str(), r.norm.c_str(), number(r.order).c_str(), number(r.low).c_str(),
                 number(r.high).c_str(), kOrderIntervalLabel, number(r.h_min).c_str(), number(r.h_max).c_str(),
                 r.points);
  close_csv(f, path);
}

std::vector<StudyRow> read_results_csv(const std::string& path) {
  const CsvReader csv(path, kResultsHeader);
  std::vector<StudyRow> out;
  for (const auto& row : csv.rows()) {
    StudyRow r;
    r.study = row.fields[0];
    r.method = row.fields[1];
    r.normals = row.fields[2];
    r.function = row.fields[3];
    r.h = csv.required_number(row, 4);
    r.center = int(csv.required_integer(row, 5));
    r.c = Eigen::Vector3d(csv.required_number(row, 6), csv.required_number(row, 7), csv.required_number(row, 8));
    r.vertices = csv.required_integer(row, 9);
    r.faces = csv.required_integer(row, 10);
    r.error_linf = csv.number(row, 11);
    r.error_l2 = csv.number(row, 12);
    r.time_s = csv.number(row, 13);
    out.push_back(r);
  }
  return out;
}

std::vector<EigenRow> read_eigen_csv(const std::string& path) {
  const CsvReader csv(path, kEigenHeader);
  std::vector<EigenRow> out;
  for (const auto& row : csv.rows()) {
    EigenRow r;
    r.method = row.fields[1];
    r.normals = row.fields[2];
    r.h = csv.required_number(row, 3);
    r.center = int(csv.required_integer(row, 4));
    r.index = int(csv.required_integer(row, 5));
    r.exact = csv.required_number(row, 6);
    r.computed = csv.number(row, 7);
    r.relative_error = csv.number(row, 8);
    r.time_s = csv.number(row, 9);
    out.push_back(r);
  }
  return out;
}

}  // namespace corrlap
