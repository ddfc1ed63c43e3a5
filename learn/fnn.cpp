#include "softkin/learn/fnn.hpp"

#include <cassert>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

namespace softkin {

double Tansig(double n) { return 2.0 / (1.0 + std::exp(-2.0 * n)) - 1.0; }

namespace {

// Eq. 5.7 elementwise, as written (one exponential, which Eigen vectorises; std::tanh is not).
// Its absolute error is a few 1e-16 everywhere, also near 0 where the relative error grows.
void TansigInPlace(Eigen::Ref<Eigen::MatrixXd> M) {
  M.array() = 2.0 / (1.0 + (-2.0 * M.array()).exp()) - 1.0;
}

// Uniform double in [-1, 1) from a 64-bit engine (53 random bits; portable).
double UniformSym(std::mt19937_64& rng) {
  const double u = static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);  // [0, 1)
  return 2.0 * u - 1.0;
}

std::string SizesString(const std::vector<int>& sizes) {
  std::string s;
  for (std::size_t i = 0; i < sizes.size(); ++i) s += (i ? "-" : "") + std::to_string(sizes[i]);
  return s;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// MinMaxMap

MinMaxMap::MinMaxMap(int size)
    : xmin_(Eigen::VectorXd::Constant(size, -1.0)),
      xmax_(Eigen::VectorXd::Constant(size, 1.0)),
      gain_(Eigen::VectorXd::Ones(size)),
      base_(Eigen::VectorXd::Constant(size, -1.0)) {
  if (size < 0) throw std::invalid_argument("MinMaxMap: size " + std::to_string(size) + " < 0");
}

MinMaxMap::MinMaxMap(const Eigen::Ref<const Eigen::VectorXd>& xmin,
                     const Eigen::Ref<const Eigen::VectorXd>& xmax) {
  if (xmin.size() != xmax.size())
    throw std::invalid_argument("MinMaxMap: xmin has " + std::to_string(xmin.size()) +
                                " rows, xmax " + std::to_string(xmax.size()));
  const Eigen::Index n = xmin.size();
  xmin_ = xmin;
  xmax_ = xmax;
  gain_.resize(n);
  base_.resize(n);
  for (Eigen::Index r = 0; r < n; ++r) {
    if (!std::isfinite(xmin(r)) || !std::isfinite(xmax(r)))
      throw std::invalid_argument("MinMaxMap: row " + std::to_string(r) +
                                  " has a non-finite range");
    if (xmin(r) > xmax(r))
      throw std::invalid_argument("MinMaxMap: row " + std::to_string(r) + " has xmin > xmax");
    const double range = xmax(r) - xmin(r);
    if (range > 0.0 && std::isfinite(2.0 / range)) {
      gain_(r) = 2.0 / range;
      base_(r) = -1.0;
    } else {  // constant row: the training constant maps to 0, deviations pass through
      gain_(r) = 1.0;
      base_(r) = 0.0;
    }
  }
}

MinMaxMap MinMaxMap::Fit(const Eigen::Ref<const Eigen::MatrixXd>& X) {
  if (X.rows() < 1) throw std::invalid_argument("MinMaxMap::Fit: no samples");
  if (!X.allFinite())
    throw std::invalid_argument("MinMaxMap::Fit: the data has non-finite entries");
  const Eigen::VectorXd lo = X.colwise().minCoeff().transpose();
  const Eigen::VectorXd hi = X.colwise().maxCoeff().transpose();
  return MinMaxMap(lo, hi);
}

void MinMaxMap::Apply(const Eigen::Ref<const Eigen::VectorXd>& x,
                      Eigen::Ref<Eigen::VectorXd> u) const {
  assert(x.size() == size() && u.size() == size());
  u.array() = gain_.array() * (x.array() - xmin_.array()) + base_.array();
}

void MinMaxMap::Reverse(const Eigen::Ref<const Eigen::VectorXd>& u,
                        Eigen::Ref<Eigen::VectorXd> x) const {
  assert(x.size() == size() && u.size() == size());
  x.array() = (u.array() - base_.array()) / gain_.array() + xmin_.array();
}

void MinMaxMap::ApplyColumns(Eigen::Ref<Eigen::MatrixXd> M) const {
  assert(M.rows() == size());
  for (Eigen::Index c = 0; c < M.cols(); ++c)
    M.col(c).array() = gain_.array() * (M.col(c).array() - xmin_.array()) + base_.array();
}

void MinMaxMap::ReverseColumns(Eigen::Ref<Eigen::MatrixXd> M) const {
  assert(M.rows() == size());
  for (Eigen::Index c = 0; c < M.cols(); ++c)
    M.col(c).array() = (M.col(c).array() - base_.array()) / gain_.array() + xmin_.array();
}

// ---------------------------------------------------------------------------------------------
// Fnn: shape, maps, parameters

Fnn::Fnn(const std::vector<int>& layer_sizes) : sizes_(layer_sizes) {
  if (sizes_.size() < 2)
    throw std::invalid_argument("Fnn: need at least 2 layer sizes (inputs, outputs), got " +
                                std::to_string(sizes_.size()));
  for (std::size_t l = 0; l < sizes_.size(); ++l)
    if (sizes_[l] < 1)
      throw std::invalid_argument("Fnn: layer size " + std::to_string(l) + " is " +
                                  std::to_string(sizes_[l]) + ", expected >= 1");
  const int L = static_cast<int>(sizes_.size()) - 1;
  W_.resize(L);
  b_.resize(L);
  num_parameters_ = 0;
  for (int l = 1; l <= L; ++l) {
    W_[l - 1] = Eigen::MatrixXd::Zero(sizes_[l], sizes_[l - 1]);
    b_[l - 1] = Eigen::VectorXd::Zero(sizes_[l]);
    num_parameters_ += sizes_[l] * (sizes_[l - 1] + 1);
  }
  in_map_ = MinMaxMap(sizes_.front());
  out_map_ = MinMaxMap(sizes_.back());
}

Fnn Fnn::WithHiddenLayers(int inputs, const std::vector<int>& hidden, int outputs) {
  std::vector<int> sizes;
  sizes.push_back(inputs);
  sizes.insert(sizes.end(), hidden.begin(), hidden.end());
  sizes.push_back(outputs);
  return Fnn(sizes);
}

double Fnn::CountParameters(int inputs, const std::vector<int>& hidden, int outputs) {
  double w = 0, prev = inputs;
  for (int h : hidden) {
    w += static_cast<double>(h) * (prev + 1);
    prev = h;
  }
  return w + static_cast<double>(outputs) * (prev + 1);
}

int Fnn::parameter_offset(int l) const {
  assert(l >= 1 && l <= num_layers());
  int off = 0;
  for (int k = 1; k < l; ++k) off += sizes_[k] * (sizes_[k - 1] + 1);
  return off;
}

std::string Fnn::Describe() const {
  if (sizes_.empty()) return "empty";
  return SizesString(sizes_) + (num_layers() > 1 ? " tansig/linear" : " linear");
}

void Fnn::FitNormalization(const Eigen::Ref<const Eigen::MatrixXd>& X,
                           const Eigen::Ref<const Eigen::MatrixXd>& Y) {
  if (X.rows() != Y.rows())
    throw std::invalid_argument("Fnn::FitNormalization: X has " + std::to_string(X.rows()) +
                                " samples, Y " + std::to_string(Y.rows()));
  if (X.cols() != num_inputs() || Y.cols() != num_outputs())
    throw std::invalid_argument("Fnn::FitNormalization: data is " + std::to_string(X.cols()) +
                                " -> " + std::to_string(Y.cols()) + " columns, network " +
                                Describe());
  in_map_ = MinMaxMap::Fit(X);
  out_map_ = MinMaxMap::Fit(Y);
}

void Fnn::set_input_map(const MinMaxMap& m) {
  if (m.size() != num_inputs())
    throw std::invalid_argument("Fnn::set_input_map: map of size " + std::to_string(m.size()) +
                                ", network has " + std::to_string(num_inputs()) + " inputs");
  in_map_ = m;
}

void Fnn::set_output_map(const MinMaxMap& m) {
  if (m.size() != num_outputs())
    throw std::invalid_argument("Fnn::set_output_map: map of size " + std::to_string(m.size()) +
                                ", network has " + std::to_string(num_outputs()) + " outputs");
  out_map_ = m;
}

void Fnn::InitializeNguyenWidrow(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const int L = num_layers();
  for (int l = 1; l < L; ++l) {  // hidden tansig layers
    Eigen::MatrixXd& W = W_[l - 1];
    const int H = sizes_[l], n = sizes_[l - 1];
    const double beta = 0.7 * std::pow(static_cast<double>(H), 1.0 / n);
    for (int i = 0; i < H; ++i) {
      for (int j = 0; j < n; ++j) W(i, j) = UniformSym(rng);
      double norm = W.row(i).norm();
      while (norm == 0.0) {  // measure-zero event; redraw
        for (int j = 0; j < n; ++j) W(i, j) = UniformSym(rng);
        norm = W.row(i).norm();
      }
      W.row(i) *= beta / norm;
    }
    for (int i = 0; i < H; ++i) b_[l - 1](i) = beta * UniformSym(rng);
  }
  Eigen::MatrixXd& Wout = W_[L - 1];
  const double scale = 1.0 / std::sqrt(static_cast<double>(sizes_[L - 1]));
  for (int j = 0; j < Wout.cols(); ++j)
    for (int i = 0; i < Wout.rows(); ++i) Wout(i, j) = scale * UniformSym(rng);
  b_[L - 1].setZero();
}

Eigen::VectorXd Fnn::parameters() const {
  Eigen::VectorXd w(num_parameters_);
  int off = 0;
  for (int l = 0; l < num_layers(); ++l) {
    const Eigen::Index nw = W_[l].size();
    w.segment(off, nw) = Eigen::Map<const Eigen::VectorXd>(W_[l].data(), nw);
    off += static_cast<int>(nw);
    w.segment(off, b_[l].size()) = b_[l];
    off += static_cast<int>(b_[l].size());
  }
  return w;
}

void Fnn::set_parameters(const Eigen::Ref<const Eigen::VectorXd>& w) {
  assert(w.size() == num_parameters_);
  int off = 0;
  for (int l = 0; l < num_layers(); ++l) {
    const Eigen::Index nw = W_[l].size();
    Eigen::Map<Eigen::VectorXd>(W_[l].data(), nw) = w.segment(off, nw);
    off += static_cast<int>(nw);
    b_[l] = w.segment(off, b_[l].size());
    off += static_cast<int>(b_[l].size());
  }
}

// ---------------------------------------------------------------------------------------------
// Fnn: evaluation

void Fnn::Forward(const Eigen::Ref<const Eigen::VectorXd>& x, FnnWorkspace& ws,
                  Eigen::Ref<Eigen::VectorXd> y) const {
  const int L = num_layers();
  assert(L >= 1 && x.size() == num_inputs() && y.size() == num_outputs());
  if (static_cast<int>(ws.a.size()) != L) ws.a.resize(L);
  for (int l = 0; l < L; ++l)
    if (ws.a[l].size() != sizes_[l]) ws.a[l].resize(sizes_[l]);
  in_map_.Apply(x, ws.a[0]);
  for (int l = 1; l < L; ++l) {
    ws.a[l].noalias() = W_[l - 1] * ws.a[l - 1];
    ws.a[l] += b_[l - 1];
    TansigInPlace(ws.a[l]);
  }
  ws.z.resize(num_outputs());
  ws.z.noalias() = W_[L - 1] * ws.a[L - 1];
  ws.z += b_[L - 1];
  out_map_.Reverse(ws.z, y);
}

Eigen::VectorXd Fnn::Forward(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  FnnWorkspace ws;
  Eigen::VectorXd y(num_outputs());
  Forward(x, ws, y);
  return y;
}

void Fnn::ForwardNormalized(const Eigen::Ref<const Eigen::MatrixXd>& U, FnnBlockWorkspace& ws,
                            Eigen::Ref<Eigen::MatrixXd> Z) const {
  const int L = num_layers();
  const Eigen::Index B = U.cols();
  assert(U.rows() == num_inputs() && Z.rows() == num_outputs() && Z.cols() == B);
  if (static_cast<int>(ws.a.size()) != L) ws.a.resize(L);
  for (int l = 1; l < L; ++l) {
    ws.a[l].resize(sizes_[l], B);
    if (l == 1)
      ws.a[l].noalias() = W_[0] * U;
    else
      ws.a[l].noalias() = W_[l - 1] * ws.a[l - 1];
    ws.a[l].colwise() += b_[l - 1];
    TansigInPlace(ws.a[l]);
  }
  if (L == 1)
    Z.noalias() = W_[0] * U;
  else
    Z.noalias() = W_[L - 1] * ws.a[L - 1];
  Z.colwise() += b_[L - 1];
}

Eigen::MatrixXd Fnn::ForwardBatch(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  assert(X.cols() == num_inputs());
  Eigen::MatrixXd U = X.transpose();
  in_map_.ApplyColumns(U);
  Eigen::MatrixXd Z(num_outputs(), X.rows());
  FnnBlockWorkspace ws;
  ForwardNormalized(U, ws, Z);
  out_map_.ReverseColumns(Z);
  return Z.transpose();
}

void Fnn::InputJacobian(const Eigen::Ref<const Eigen::VectorXd>& x, FnnWorkspace& ws,
                        Eigen::Ref<Eigen::VectorXd> y, Eigen::Ref<Eigen::MatrixXd> J) const {
  const int L = num_layers();
  const int n0 = num_inputs();
  assert(J.rows() == num_outputs() && J.cols() == n0);
  Forward(x, ws, y);
  // d a_0 / d x = diag(gain_in); d a_l / d x = diag(1 - a_l^2) W_l d a_{l-1} / d x;
  // dy/dx = diag(1 / gain_out) W_L d a_{L-1} / dx.
  if (L == 1) {
    J.noalias() = W_[0] * in_map_.gain().asDiagonal();
  } else {
    if (static_cast<int>(ws.m.size()) != L) ws.m.resize(L);
    for (int l = 1; l < L; ++l) {
      Eigen::MatrixXd& m = ws.m[l];
      if (m.rows() != sizes_[l] || m.cols() != n0) m.resize(sizes_[l], n0);
      if (l == 1)
        m.noalias() = W_[0] * in_map_.gain().asDiagonal();
      else
        m.noalias() = W_[l - 1] * ws.m[l - 1];
      for (int i = 0; i < sizes_[l]; ++i) m.row(i) *= 1.0 - ws.a[l](i) * ws.a[l](i);
    }
    J.noalias() = W_[L - 1] * ws.m[L - 1];
  }
  for (int k = 0; k < num_outputs(); ++k) J.row(k) /= out_map_.gain()(k);
}

Eigen::MatrixXd Fnn::InputJacobian(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  FnnWorkspace ws;
  Eigen::VectorXd y(num_outputs());
  Eigen::MatrixXd J(num_outputs(), num_inputs());
  InputJacobian(x, ws, y, J);
  return J;
}

Eigen::MatrixXd Fnn::InputJacobianBatch(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  assert(X.cols() == num_inputs());
  const int no = num_outputs();
  Eigen::MatrixXd out(X.rows() * no, num_inputs());
  FnnWorkspace ws;
  Eigen::VectorXd y(no), x(num_inputs());
  Eigen::MatrixXd J(no, num_inputs());
  for (Eigen::Index s = 0; s < X.rows(); ++s) {
    x = X.row(s).transpose();
    InputJacobian(x, ws, y, J);
    out.middleRows(s * no, no) = J;
  }
  return out;
}

void Fnn::ParameterJacobianNormalized(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                      FnnBlockWorkspace& ws, Eigen::Ref<Eigen::MatrixXd> Z,
                                      Eigen::Ref<Eigen::MatrixXd> Jt) const {
  const int L = num_layers();
  const int nL = num_outputs();
  const Eigen::Index B = U.cols();
  assert(Jt.rows() == num_parameters_ && Jt.cols() == B * nL);
  ForwardNormalized(U, ws, Z);
  // Activations feeding each layer: A(l) = a_{l-1} (n_{l-1} x B), a_0 = U.
  auto A = [&](int l) -> const Eigen::Ref<const Eigen::MatrixXd> {
    if (l == 1) return U;
    return ws.a[l - 1];
  };
  if (static_cast<int>(ws.d.size()) != L) ws.d.resize(L);
  const int offL = parameter_offset(L);
  const int nprev = sizes_[L - 1];
  for (int k = 0; k < nL; ++k) {
    // Output layer: d z_k / d W_L(i, j) = [i == k] a_{L-1}(j); d z_k / d b_L(i) = [i == k].
    {
      const Eigen::Ref<const Eigen::MatrixXd> Aprev = A(L);
      for (Eigen::Index s = 0; s < B; ++s) {
        auto col = Jt.col(s * nL + k);
        col.segment(offL, nL * nprev + nL).setZero();
        for (int j = 0; j < nprev; ++j) col(offL + j * nL + k) = Aprev(j, s);
        col(offL + nL * nprev + k) = 1.0;
      }
    }
    // Hidden layers, backwards: d_{L-1} = diag(1 - a^2) W_L^T e_k; d_{l-1} = diag(1 - a^2) W_l^T
    // d_l.
    for (int l = L - 1; l >= 1; --l) {
      Eigen::MatrixXd& d = ws.d[l];
      d.resize(sizes_[l], B);
      if (l == L - 1)
        d = W_[L - 1].row(k).transpose().replicate(1, B);
      else
        d.noalias() = W_[l].transpose() * ws.d[l + 1];
      d.array() *= 1.0 - ws.a[l].array().square();
      const Eigen::Ref<const Eigen::MatrixXd> Aprev = A(l);
      const int off = parameter_offset(l);
      const int nl = sizes_[l], np = sizes_[l - 1];
      for (Eigen::Index s = 0; s < B; ++s) {
        auto col = Jt.col(s * nL + k);
        for (int j = 0; j < np; ++j) col.segment(off + j * nl, nl) = Aprev(j, s) * d.col(s);
        col.segment(off + nl * np, nl) = d.col(s);
      }
    }
  }
}

Eigen::MatrixXd Fnn::ParameterJacobian(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  Eigen::MatrixXd U(num_inputs(), 1);
  in_map_.Apply(x, U.col(0));
  Eigen::MatrixXd Z(num_outputs(), 1);
  Eigen::MatrixXd Jt(num_parameters_, num_outputs());
  FnnBlockWorkspace ws;
  ParameterJacobianNormalized(U, ws, Z, Jt);
  Eigen::MatrixXd J = Jt.transpose();
  for (int k = 0; k < num_outputs(); ++k) J.row(k) /= out_map_.gain()(k);
  return J;
}

}  // namespace softkin
