#pragma once
// NumPy arrays over the library's buffers: no copy, the owner kept alive by the array's base.

#include <array>
#include <cstddef>
#include <memory>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

namespace scanplan::python {

/// A read-only array of `shape` over `data` with byte `strides`, keeping `owner` (any shared_ptr)
/// alive for as long as the array lives.
template <class T, class Owner>
pybind11::array_t<T> viewOf(const T* data,
                            std::vector<pybind11::ssize_t> shape,
                            std::vector<pybind11::ssize_t> strides,
                            std::shared_ptr<Owner> owner) {
  auto* keep = new std::shared_ptr<Owner>(std::move(owner));
  pybind11::capsule base(keep, [](void* p) { delete static_cast<std::shared_ptr<Owner>*>(p); });
  pybind11::array_t<T> array(std::move(shape), std::move(strides), data, base);
  pybind11::detail::array_proxy(array.ptr())->flags &=
      ~pybind11::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return array;
}

/// An (n, k) array of `vectors` (Eigen fixed-size vectors of k doubles or ints), viewed in place.
template <class T, class Vector, class Owner>
pybind11::array_t<T> matrixOf(const std::vector<Vector>& vectors, std::shared_ptr<Owner> owner) {
  constexpr auto k = static_cast<pybind11::ssize_t>(Vector::RowsAtCompileTime);
  return viewOf<T>(
      vectors.empty() ? nullptr : vectors.front().data(),
      {static_cast<pybind11::ssize_t>(vectors.size()), k},
      {static_cast<pybind11::ssize_t>(sizeof(Vector)), static_cast<pybind11::ssize_t>(sizeof(T))},
      std::move(owner));
}

}  // namespace scanplan::python
