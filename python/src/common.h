// SPDX-License-Identifier: MIT
/// \file
/// What every part of the Python module shares: NumPy arrays in (any real dtype, copied only when
/// it differs from the C++ side's or is not C-contiguous; a wrong shape or non-numeric data is a
/// one-line `isokit.InputError` naming the argument), long calls with the GIL released and a
/// progress callback that also lets Ctrl+C interrupt them.
#pragma once

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

#include "isokit/core/error.h"
#include "isokit/track/mesh.h"

namespace isokit::python {

namespace py = pybind11;

/// `obj` as a C-contiguous array of T, without a copy when it already is one; other real dtypes
/// (bool, integers, floats) are converted. `shape`: the expected shape, -1 for any extent; an
/// empty `shape` accepts any. \throw InputError "argument 'NAME': ..." otherwise.
template <class T>
py::array_t<T, py::array::c_style> real_array(py::handle obj, const char* name,
                                              std::vector<py::ssize_t> shape = {}) {
  py::array a = py::array::ensure(obj);
  if (!a)
    throw InputError(std::string("argument '") + name + "': expected an array of numbers, got " +
                     std::string(py::str(py::type::of(obj).attr("__name__"))));
  const char kind = a.dtype().kind();
  if (kind != 'b' && kind != 'i' && kind != 'u' && kind != 'f')
    throw InputError(std::string("argument '") + name + "': expected real numbers, got dtype " +
                     std::string(py::str(a.dtype())));
  auto out = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!out) throw InputError(std::string("argument '") + name + "': cannot be read as " + typeid(T).name());
  if (!shape.empty()) {
    bool ok = out.ndim() == static_cast<py::ssize_t>(shape.size());
    for (std::size_t k = 0; ok && k < shape.size(); ++k) ok = shape[k] < 0 || out.shape(k) == shape[k];
    if (!ok) {
      auto text = [](auto begin, auto end) {
        std::string s = "(";
        for (auto it = begin; it != end; ++it)
          s += (it == begin ? "" : ", ") + (*it < 0 ? std::string("N") : std::to_string(*it));
        return s + (std::distance(begin, end) == 1 ? ",)" : ")");
      };
      std::vector<py::ssize_t> got(out.shape(), out.shape() + out.ndim());
      throw InputError(std::string("argument '") + name + "': expected shape " +
                       text(shape.begin(), shape.end()) + ", got " + text(got.begin(), got.end()));
    }
  }
  return out;
}

/// `obj` as `#V by 3` float positions (`rows` of them, -1 for any number). \throw InputError.
inline track::Positions positions_of(const py::object& obj, const char* name, py::ssize_t rows = -1) {
  const auto a = real_array<float>(obj, name, {rows, 3});
  track::Positions p(a.shape(0), 3);
  if (a.size() > 0) std::memcpy(p.data(), a.data(), static_cast<std::size_t>(a.size()) * sizeof(float));
  return p;
}

/// `obj` as `#F by 3` vertex indices. \throw InputError.
inline track::Triangles triangles_of(const py::object& obj, const char* name) {
  const auto t = real_array<int>(obj, name, {-1, 3});
  track::Triangles f(t.shape(0), 3);
  if (t.size() > 0) std::memcpy(f.data(), t.data(), static_cast<std::size_t>(t.size()) * sizeof(int));
  return f;
}

/// Long C++ work with the GIL released, calling back into Python (a progress callback, a field
/// written in Python) on any thread: `call` takes the GIL, runs the Python code and, when it raises
/// — or Ctrl+C was pressed — keeps the Python error and stops the C++ work with an exception of its
/// own; `run` then raises that error in the caller. Calls into Python are serialised.
class Released {
 public:
  /// Runs `work()` without the GIL; re-raises a Python error that `call` kept.
  void run(const std::function<void()>& work);
  /// Runs `python()` with the GIL held (from any thread). \throw Stopped after a Python error.
  void call(const std::function<void()>& python);
  /// A progress function for C++ code: calls `callback(done, total)` when it is not None, and
  /// checks for Ctrl+C. `callback` must outlive the work.
  std::function<void(int, int)> progress(const py::object& callback);

  struct Stopped {};

 private:
  std::mutex mutex_;
  bool stopped_{false};
  PyObject* type_{nullptr};
  PyObject* value_{nullptr};
  PyObject* traceback_{nullptr};
};

void bind_operators(py::module_& m);
void bind_fields(py::module_& m);
void bind_tracker(py::module_& m);
void bind_skinning(py::module_& m);

/// The Python type of isokit.InputError (set when the module is imported).
extern PyObject* input_error_type;

}  // namespace isokit::python
