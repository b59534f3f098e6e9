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

#include <functional>
#include <string>
#include <vector>

#include "isokit/core/error.h"

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

/// Runs `work(progress)` with the GIL released. `callback` (a Python callable or None) gets
/// `(done, total)` from `progress`, which is called on any thread; Ctrl+C (or an exception in the
/// callback) stops the work at its next progress report and is raised in the caller.
void run_released(const py::object& callback,
                  const std::function<void(const std::function<void(int, int)>&)>& work);

void bind_operators(py::module_& m);
void bind_fields(py::module_& m);

}  // namespace isokit::python
