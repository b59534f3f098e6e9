// SPDX-License-Identifier: MIT
// The `isokit._isokit` extension: errors, threads, the shared helpers (common.h) and the parts.
#include <Python.h>

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <memory>
#include <mutex>

#include "common.h"

namespace isokit::python {

namespace {

/// Thrown on a worker thread when the Python side asked to stop (Ctrl+C, or an exception raised
/// by the progress callback); the Python error waits in `Stop::pending` for the caller.
struct Stop {
  PyObject* type{nullptr};
  PyObject* value{nullptr};
  PyObject* traceback{nullptr};
};

std::unique_ptr<tbb::global_control> thread_limit;

}  // namespace

void run_released(const py::object& callback,
                  const std::function<void(const std::function<void(int, int)>&)>& work) {
  std::mutex m;
  Stop pending;
  bool stopped = false;
  const bool has_callback = !callback.is_none();
  auto progress = [&](int done, int total) {
    std::lock_guard<std::mutex> lock(m);
    if (stopped) throw Stop{};
    py::gil_scoped_acquire gil;
    bool failed = PyErr_CheckSignals() != 0;
    if (!failed && has_callback) {
      try {
        callback(done, total);
      } catch (py::error_already_set& e) {
        e.restore();
        failed = true;
      }
    }
    if (failed) {
      PyErr_Fetch(&pending.type, &pending.value, &pending.traceback);
      stopped = true;
      throw Stop{};
    }
  };
  try {
    py::gil_scoped_release release;
    work(progress);
  } catch (const Stop&) {
  }
  if (stopped) {
    PyErr_Restore(pending.type, pending.value, pending.traceback);
    throw py::error_already_set();
  }
}

}  // namespace isokit::python

PYBIND11_MODULE(_isokit, m) {
  namespace py = pybind11;
  using namespace isokit::python;
  m.doc() = "isokit: implicit composition, operator design and iso-surface tracking (C++ core)";
  m.attr("__version__") = ISOKIT_VERSION;
  // isokit::InputError (bad input: a file, an argument) -> isokit.InputError, a ValueError.
  static py::exception<isokit::InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const isokit::InputError& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    }
  });
  m.def(
      "set_num_threads",
      [](int n) {
        if (n < 0)
          throw isokit::InputError("argument 'n': must be >= 0 (0: every hardware thread), got " +
                                   std::to_string(n));
        thread_limit.reset();
        if (n > 0)
          thread_limit =
              std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, n);
      },
      py::arg("n"), "Limits isokit's parallel work to n threads (0: every hardware thread, the default).");
  m.def(
      "get_num_threads",
      [] {
        return static_cast<int>(
            tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
      },
      "The number of threads isokit's parallel work may use.");
  py::module_ ops =
      m.def_submodule("operators", "Composition operators: profiles, the biharmonic generator, controllers");
  bind_operators(ops);
  py::module_ fields = m.def_submodule("fields", "Fields: primitives, HRBFs, grids and their compositions");
  bind_fields(fields);
}
