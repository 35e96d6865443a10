// corrlap._core: the compiled half of the Python package corrlap (python/corrlap/__init__.py).
// corrlap's errors become Python's: InputError (bad input, files) -> ValueError, NumericalError and
// SolverError (a failed solve) -> RuntimeError, with the C++ message.
#include <corrlap/core/error.hpp>
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
  m.def("set_threads", &corrlap::set_thread_count, py::arg("n"));
  m.def("get_threads", &corrlap::thread_count);
}
