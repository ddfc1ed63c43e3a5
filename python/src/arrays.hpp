#pragma once
/// \file arrays.hpp
/// NumPy arrays in and out of the bindings: shape checks whose messages name the argument and the
/// shape expected, and copies into Eigen.
#include <Eigen/Core>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <stdexcept>
#include <string>

namespace softkin {
namespace python {

namespace py = pybind11;

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IntArray = py::array_t<long long, py::array::c_style | py::array::forcecast>;

inline std::string ShapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

/// Rows x cols (cols > 0) or, with cols = -1, any column count among `allowed` (e.g. 4 or 6).
inline void CheckMatrix(const py::array& a, const std::string& what, long long cols,
                        const std::string& expected) {
  if (a.ndim() != 2 || (cols > 0 && a.shape(1) != cols))
    throw std::invalid_argument(what + ": expected an array of shape " + expected + ", got shape " +
                                ShapeText(a));
}

/// A #rows x 3 array of finite numbers as an Eigen matrix (mm).
inline Eigen::MatrixX3d ToPoints(const DoubleArray& a, const std::string& what) {
  CheckMatrix(a, what, 3, "(n, 3)");
  Eigen::MatrixX3d X(a.shape(0), 3);
  auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    for (int d = 0; d < 3; ++d) X(i, d) = r(i, d);
  return X;
}

/// A vector of `n` numbers (n < 0: any length); a scalar counts as length 1.
inline Eigen::VectorXd ToVector(const DoubleArray& a, long long n, const std::string& what) {
  if (a.ndim() > 1 || (n >= 0 && a.size() != n))
    throw std::invalid_argument(
        what + ": expected " +
        (n >= 0 ? std::to_string(n) + " value" + (n == 1 ? "" : "s") : std::string("a vector")) +
        ", got an array of shape " + ShapeText(a));
  Eigen::VectorXd v(a.size());
  for (py::ssize_t i = 0; i < a.size(); ++i) v(i) = a.data()[i];
  return v;
}

/// An Eigen matrix as a new NumPy array (row-major copy).
template <typename Derived>
py::array_t<double> ToNumpy(const Eigen::MatrixBase<Derived>& m) {
  py::array_t<double> out({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto w = out.template mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) w(i, j) = m(i, j);
  return out;
}

/// An Eigen vector as a new 1-D NumPy array.
inline py::array_t<double> ToNumpyVector(const Eigen::Ref<const Eigen::VectorXd>& v) {
  py::array_t<double> out(v.size());
  for (Eigen::Index i = 0; i < v.size(); ++i) out.mutable_data()[i] = v(i);
  return out;
}

/// Integer indices as a new 1-D NumPy array.
template <typename Vec>
py::array_t<long long> ToIndexArray(const Vec& v) {
  py::array_t<long long> out(static_cast<py::ssize_t>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) out.mutable_data()[i] = v[i];
  return out;
}

}  // namespace python
}  // namespace softkin
