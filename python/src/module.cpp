// corrlap._core: the compiled half of the Python package corrlap (python/corrlap/__init__.py).
// corrlap's errors become Python's: InputError (bad input, files) -> ValueError, NumericalError and
// SolverError (a failed solve) -> RuntimeError, with the C++ message.
#include <pybind11/stl.h>

#include <corrlap/core/error.hpp>
#include <corrlap/core/memory_budget.hpp>
#include <corrlap/core/threads.hpp>

#include "bindings.hpp"

PYBIND11_MODULE(_core, m) {
  namespace py = pybind11;
  using namespace corrlap::python;
  m.doc() = "corrlap's C++ library; use the package corrlap, which documents every function";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const corrlap::InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const corrlap::Error& e) {
      PyErr_SetString(PyExc_RuntimeError, e.what());
    }
  });
  bind_surface(m);
  bind_normals(m);
  bind_operators(m);
  bind_solvers(m);
  bind_regularization(m);
  bind_view(m);
  m.def("set_threads", &corrlap::set_thread_count, py::arg("n"));
  m.def("get_threads", &corrlap::thread_count);
  // The memory budget every allocation sized by the input is checked against (core/memory_budget.hpp):
  // CORRLAP_MAX_MEMORY as for the CLI, else the machine's memory, until set_max_memory.
  corrlap::apply_memory_budget_from_environment();
  m.def(
      "set_max_memory",
      [](const std::optional<std::string>& size) {
        corrlap::set_memory_budget(size ? corrlap::parse_memory_size(*size) : 0);
      },
      py::arg("size"));
  m.def("get_max_memory", &corrlap::memory_budget);
}
