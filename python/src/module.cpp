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

std::unique_ptr<tbb::global_control> thread_limit;

}  // namespace

PyObject* input_error_type = PyExc_ValueError;

void Released::call(const std::function<void()>& python) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (stopped_) throw Stopped{};
  py::gil_scoped_acquire gil;
  bool failed = PyErr_CheckSignals() != 0;
  if (!failed) {
    try {
      python();
    } catch (py::error_already_set& e) {
      e.restore();
      failed = true;
    } catch (const InputError& e) {
      PyErr_SetString(input_error_type, e.what());
      failed = true;
    }
  }
  if (failed) {
    PyErr_Fetch(&type_, &value_, &traceback_);
    stopped_ = true;
    throw Stopped{};
  }
}

std::function<void(int, int)> Released::progress(const py::object& callback) {
  // Copies of the function are made without the GIL: it holds the callback by pointer (the
  // caller's argument outlives the work), not a py::object whose copy would touch its refcount.
  const py::object* cb = &callback;
  return [this, cb](int done, int total) {
    call([&] {
      if (!cb->is_none()) (*cb)(done, total);
    });
  };
}

void Released::run(const std::function<void()>& work) {
  try {
    py::gil_scoped_release release;
    work();
  } catch (const Stopped&) {
  }
  if (stopped_) {
    PyErr_Restore(type_, value_, traceback_);
    type_ = value_ = traceback_ = nullptr;
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
  input_error_type = input_error.ptr();
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
  py::module_ tracker = m.def_submodule("tracker", "The 2014 iso-surface tracker on NumPy meshes");
  bind_tracker(tracker);
#ifdef ISOKIT_PYTHON_SKINNING
  py::module_ skinning = m.def_submodule("skinning", "Rigs, implicit skins and bakes (as isokit-skin)");
  bind_skinning(skinning);
#endif
}
