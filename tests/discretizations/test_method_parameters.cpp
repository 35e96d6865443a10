// Typed method parameters (core/parameters.hpp) and the one assembly entry point
// (Discretization::assemble_into): walks the registry and checks, for every method, that each
// declared parameter is the one place of its default, that bad values get the one wording, that
// every parameter reaches the CLI's flags and the docs table, and that every path of assembly
// (one-shot, with a pattern, refill) fills every field of Operators, contract_risk included.
#include <doctest/doctest.h>

#include <corrlap/core/error.hpp>
#include <corrlap/core/parameters.hpp>
#include <corrlap/discretizations/assembly/quad_pattern.hpp>
#include <corrlap/discretizations/detail/normal_policy.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <fstream>
#include <sstream>

#include "discretizations/reference_support.hpp"

using namespace corrlap;

namespace {

bool same_bits(const Eigen::SparseMatrix<double>& A, const Eigen::SparseMatrix<double>& B) {
  if (A.rows() != B.rows() || A.cols() != B.cols() || A.nonZeros() != B.nonZeros()) return false;
  for (int c = 0; c < A.outerSize(); ++c) {
    Eigen::SparseMatrix<double>::InnerIterator a(A, c), b(B, c);
    for (; a && b; ++a, ++b)
      if (a.index() != b.index() || a.value() != b.value()) return false;
    if (a || b) return false;
  }
  return true;
}

bool same_optional(const std::optional<Eigen::SparseMatrix<double>>& a,
                   const std::optional<Eigen::SparseMatrix<double>>& b) {
  return a.has_value() == b.has_value() && (!a || same_bits(*a, *b));
}

// Every field of Operators, compared exactly.
void check_same_operators(const Operators& a, const Operators& b) {
  CHECK(same_bits(a.L, b.L));
  CHECK(same_bits(a.M, b.M));
  CHECK(same_optional(a.M_lumped, b.M_lumped));
  CHECK(same_optional(a.D0, b.D0));
  CHECK(same_optional(a.sharp, b.sharp));
  CHECK(same_optional(a.flat, b.flat));
  CHECK(same_optional(a.M1, b.M1));
  CHECK(a.domain == b.domain);
  CHECK(a.warnings == b.warnings);
  CHECK(a.contract_risk == b.contract_risk);
}

// A unit normal at u.n = -0.01 from the surfel normal n: inconsistent, but every measure stays
// finite and non-zero (an exactly tangent normal gives zero areas, and NaN is not equal to itself).
Eigen::RowVector3d slightly_inward(const Eigen::Vector3d& n) {
  return (n.unitOrthogonal() - 0.01 * n).normalized().transpose();
}

Config with_value(const Parameter& p, const std::string& text) {
  Config c;
  switch (p.type) {
    case ParameterType::Real:
    case ParameterType::Integer:
      c.set(p.name, std::stod(text));
      break;
    case ParameterType::Boolean:
      c.set(p.name, text == "true");
      break;
    case ParameterType::Choice:
      c.set(p.name, text);
      break;
  }
  return c;
}

}  // namespace

TEST_CASE("every method's declared parameters are well formed") {
  for (const std::string& name : discretization_registry().names()) {
    CAPTURE(name);
    const ParameterList& params = make_discretization(name)->parameters();
    for (const Parameter& p : params.items()) {
      CAPTURE(p.name);
      CHECK_FALSE(p.doc.empty());
      CHECK(p.name.find_first_not_of("abcdefghijklmnopqrstuvwxyz_0123456789") == std::string::npos);
      CHECK(params.find(p.name) == &p);  // one declaration per name
      CHECK_FALSE(p.default_text().empty());
      if (p.type == ParameterType::Choice) {
        REQUIRE_FALSE(p.choices.empty());
        CHECK(p.choices.front() == p.default_value);
      }
      // The default is valid under its own declaration.
      if (!p.default_value.empty()) CHECK_NOTHROW((void)params.read(with_value(p, p.default_value), name));
    }
  }
}

TEST_CASE("a parameter's declared default is the value the method uses (one place per default)") {
  const test::SphereCase s = test::sphere_case(0.25);
  for (const std::string& name : discretization_registry().names()) {
    CAPTURE(name);
    const auto d = make_discretization(name);
    const Operators plain = d->assemble(s.mesh, s.normals, Config());
    for (const Parameter& p : d->parameters().items()) {
      if (p.default_value.empty()) continue;  // computed from the input (heat-kernel t)
      CAPTURE(p.name);
      const Operators given = d->assemble(s.mesh, s.normals, with_value(p, p.default_value));
      check_same_operators(plain, given);
    }
  }
}

TEST_CASE("bad parameter values get one wording, tagged with the parameter's name") {
  const test::SphereCase s = test::sphere_case(0.5);
  for (const std::string& name : discretization_registry().names()) {
    CAPTURE(name);
    const auto d = make_discretization(name);
    for (const Parameter& p : d->parameters().items()) {
      CAPTURE(p.name);
      std::vector<Config> bad;
      Config text;
      text.set(p.name, std::string("not-a-value"));
      bad.push_back(text);
      if (std::isfinite(p.min) && p.type != ParameterType::Integer) bad.push_back(with_value(p, "-1e300"));
      if (p.type == ParameterType::Integer) bad.push_back(with_value(p, "0.5"));
      for (const Config& c : bad) {
        try {
          (void)d->assemble(s.mesh, s.normals, c);
          FAIL("accepted " << c.to_json());
        } catch (const InputError& e) {
          const std::string what = e.what();
          CHECK(e.parameter() == p.name);
          CHECK(what.rfind(name + ": " + p.name + " = ", 0) == 0);
          CHECK(what.find(": expected ") != std::string::npos);
        }
      }
    }
    Config unknown;
    unknown.set("no_such_parameter", 1.0);
    CHECK_THROWS_WITH_AS((void)d->assemble(s.mesh, s.normals, unknown), doctest::Contains("unknown config key"),
                         InputError);
  }
}

TEST_CASE("every assembly path keeps every field of Operators, contract_risk included") {
  // One face normal and one vertex normal slightly inward (u.n < 0): orientation=warn computes with
  // them as given and must say so on every path.
  test::SphereCase s = test::sphere_case(0.25);
  const Eigen::MatrixX3d trivial = trivial_face_normals(s.mesh);
  s.normals.face.row(0) = slightly_inward(trivial.row(0).transpose());
  s.normals.vertex.row(s.mesh.faces(0, 0)) = slightly_inward(trivial.row(0).transpose());
  const QuadPattern pattern = QuadPattern::build(s.mesh);
  for (const std::string& name : discretization_registry().names()) {
    CAPTURE(name);
    const auto d = make_discretization(name);
    const bool corrected = d->required_normals() != NormalKind::None;
    const Config params = corrected ? Config::from_key_values({"orientation=warn"}) : Config();
    const Operators one_shot = d->assemble(s.mesh, s.normals, params);
    CHECK(one_shot.contract_risk.empty() == !corrected);
    CHECK(one_shot.warnings.empty() == !corrected);
    check_same_operators(one_shot, d->assemble(s.mesh, s.normals, params, pattern));
    // A refill of operators that held another result (extras, a risk, warnings) replaces all of it.
    Config first;
    if (d->parameters().find("extras")) first.set("extras", true);
    Operators reused = d->assemble(s.mesh, s.normals, first);
    reused.contract_risk = "stale";
    reused.warnings = {"stale"};
    d->assemble_into(s.mesh, s.normals, params, reused);
    check_same_operators(one_shot, reused);
    reused.contract_risk = "stale";
    d->assemble_into(s.mesh, s.normals, params, pattern, reused);
    check_same_operators(one_shot, reused);
  }
}

TEST_CASE("heat-kernel keeps contract_risk on the refill path (regression)") {
  test::SphereCase s = test::sphere_case(0.25);
  const Eigen::MatrixX3d trivial = trivial_face_normals(s.mesh);
  s.normals.face.row(3) = slightly_inward(trivial.row(3).transpose());
  const auto d = make_discretization("heat-kernel");
  Operators ops;
  d->assemble_into(s.mesh, s.normals, Config::from_key_values({"orientation=warn"}), ops);
  CHECK(ops.contract_risk.find("orientation=warn") != std::string::npos);
  CHECK(ops.domain == Operators::Domain::Faces);
}

TEST_CASE("the docs table of method parameters is the one the declarations render") {
  std::ifstream in(std::string(CORRLAP_SOURCE_DIR) + "/docs/discretizations.md");
  REQUIRE(in);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string doc = ss.str();
  const std::string begin = "<!-- method-parameters: begin", end = "<!-- method-parameters: end -->";
  const auto b = doc.find(begin), e = doc.find(end);
  REQUIRE(b != std::string::npos);
  REQUIRE(e != std::string::npos);
  const std::string table = doc.substr(doc.find('\n', b) + 1, e - doc.find('\n', b) - 1);
  const std::string expected = method_parameters_markdown();
  INFO("regenerate with `corrlap methods --markdown` and paste it between the markers of docs/discretizations.md");
  CHECK(table == expected);
}

#ifdef CORRLAP_CLI
TEST_CASE("every method parameter is a flag of every command that assembles operators") {
  for (const std::string command : {"operators", "eigs", "solve", "regularize", "reconstruct", "study"}) {
    CAPTURE(command);
    std::string help;
    REQUIRE(test::run_cli_tagged("help_" + command, command + " --help", &help) == 0);
    for (const std::string& name : discretization_registry().names())
      for (const Parameter& p : make_discretization(name)->parameters().items()) {
        std::string flag = "--" + p.name;
        for (char& c : flag)
          if (c == '_') c = '-';
        CAPTURE(flag);
        CHECK(help.find(" " + flag + " ") != std::string::npos);
      }
  }
}

TEST_CASE("a flag and --param give the same parameter, errors name the flag") {
  const std::string mesh = test::sphere_ref("mesh.obj"), fn = test::sphere_ref("face_normals_true.txt");
  const std::string common = "operators --mesh " + mesh + " --face-normals " + fn + " --method polydec ";
  const std::string a = test::tmp_path("flag_lambda"), b = test::tmp_path("param_lambda");
  REQUIRE(test::run_cli_tagged("flag_lambda", common + "--lambda 0.5 --out " + a) == 0);
  REQUIRE(test::run_cli_tagged("param_lambda", common + "--param lambda=0.5 --out " + b) == 0);
  CHECK(test::read_text(a + "/L.mtx") == test::read_text(b + "/L.mtx"));
  std::string err;
  CHECK(test::run_cli_tagged("bad_lambda", common + "--lambda -1 --out " + a, nullptr, &err) == 1);
  CHECK(err.find("polydec: lambda = -1: expected >= 0 (--lambda)") != std::string::npos);
}
#endif
