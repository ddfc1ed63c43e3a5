#pragma once
/// \file
/// A feed-forward neural network (thesis §5.2.2, §5.3.4, Fig. 5.2): any number of hidden layers of
/// tansig units (Eq. 5.7, tansig(n) = 2 / (1 + exp(-2 n)) - 1) and a linear output layer, with
/// min-max normalisation of inputs and outputs to [-1, 1] stored with the network (MATLAB
/// `feedforwardnet` + `mapminmax` semantics).
///
/// Shapes. Layer sizes are {n_0, n_1, ..., n_L}: n_0 inputs, n_1..n_{L-1} hidden tansig units,
/// n_L linear outputs (L >= 1; L = 1 is a purely linear map). Batches are ROW PER SAMPLE: X is
/// #samples x n_0, Y is #samples x n_L (like Kinematics::p and a dataset table).
///
/// Evaluation of one input x (original units):
///   a_0 = N_in(x),  a_l = tansig(W_l a_{l-1} + b_l) (l < L),  z = W_L a_{L-1} + b_L,  y =
///   N_out^-1(z)
/// with W_l an n_l x n_{l-1} matrix and b_l an n_l vector.
///
/// Flat parameter vector (#parameters = sum_l n_l (n_{l-1} + 1)): for l = 1..L in order, W_l in
/// column-major order, then b_l. So W_l(i, j) sits at offset_l + j n_l + i and b_l(i) at
/// offset_l + n_l n_{l-1} + i, where offset_l is the count of all earlier layers' entries.
///
/// Normalisation (MinMaxMap, one per side): per row r, with the range [xmin_r, xmax_r] fitted from
/// data, u_r = gain_r (x_r - xmin_r) - 1 with gain_r = 2 / (xmax_r - xmin_r), so [xmin, xmax] maps
/// to [-1, 1]. A constant row (xmax_r == xmin_r) gets gain 1 and offset xmin_r: u_r = x_r - xmin_r,
/// i.e. the training constant maps to 0 and deviations pass through unscaled (no division by zero,
/// and the input Jacobian stays finite). The inverse map is x_r = (u_r + 1) / gain_r + xmin_r
/// (resp. u_r + xmin_r for a constant row).
///
/// Nguyen-Widrow initialisation (InitializeNguyenWidrow): for every hidden layer l with H = n_l
/// units and n = n_{l-1} inputs, beta = 0.7 H^(1/n); each row of W_l is drawn uniform in [-1, 1]^n
/// and rescaled to Euclidean norm beta; b_l(i) is uniform in [-beta, beta]. The linear output
/// layer gets W_L uniform in [-1, 1] / sqrt(n_{L-1}) and b_L = 0. Uniform numbers come from
/// std::mt19937_64(seed) as (r >> 11) * 2^-53 (portable: no std::uniform_real_distribution).
///
/// File format "softkin-fnn v1" (text, one record per line, '#' starts a comment line):
///   softkin-fnn v1
///   activation tansig
///   layers <L+1>
///   sizes <n_0> <n_1> ... <n_L>
///   input_min <n_0 numbers>
///   input_max <n_0 numbers>
///   output_min <n_L numbers>
///   output_max <n_L numbers>
///   parameters <#parameters>
///   <#parameters lines, one number each, in the flat layout above>
///   end
/// Numbers are written with 17 significant digits, so a round trip is bitwise exact. The loader
/// checks the magic, the version, every count and size, min <= max, finiteness of every number,
/// and the final "end"; any failure throws std::runtime_error naming the file, the line and the
/// field.

#include <Eigen/Core>

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace softkin {

/// Eq. 5.7: tansig(n) = 2 / (1 + exp(-2 n)) - 1 (= tanh(n) to a few 1e-16 absolute; the network
/// evaluates this form, vectorised).
double Tansig(double n);

/// Per-row min-max map of vectors of length size() to [-1, 1] (MATLAB mapminmax, see the file
/// comment for constant rows).
class MinMaxMap {
 public:
  MinMaxMap() = default;
  /// Identity-like map of `size` rows with range [-1, 1] (gain 1, u = x).
  explicit MinMaxMap(int size);
  /// A map with the given per-row range. Throws std::invalid_argument if the sizes differ, an entry
  /// is not finite, or xmin > xmax (naming the row).
  MinMaxMap(const Eigen::Ref<const Eigen::VectorXd>& xmin,
            const Eigen::Ref<const Eigen::VectorXd>& xmax);
  /// Range fitted from data: X is #samples x size (row per sample), #samples >= 1, all finite.
  /// Throws std::invalid_argument otherwise.
  static MinMaxMap Fit(const Eigen::Ref<const Eigen::MatrixXd>& X);

  int size() const { return static_cast<int>(xmin_.size()); }
  const Eigen::VectorXd& xmin() const { return xmin_; }
  const Eigen::VectorXd& xmax() const { return xmax_; }
  /// d u / d x per row (2 / range, or 1 for a constant row).
  const Eigen::VectorXd& gain() const { return gain_; }

  /// u = N(x), x and u of length size(). u may alias x.
  void Apply(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> u) const;
  /// x = N^-1(u). x may alias u.
  void Reverse(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> x) const;
  /// In place on a size() x B matrix, column per sample: M <- N(M).
  void ApplyColumns(Eigen::Ref<Eigen::MatrixXd> M) const;
  /// In place on a size() x B matrix, column per sample: M <- N^-1(M).
  void ReverseColumns(Eigen::Ref<Eigen::MatrixXd> M) const;

 private:
  Eigen::VectorXd xmin_, xmax_, gain_;
  Eigen::VectorXd base_;  // -1 per row, 0 for a constant row: u = gain (x - xmin) + base
};

/// Scratch memory for single-input evaluations, so that Forward / InputJacobian with a workspace do
/// not allocate after the first call with a given network shape. One workspace per thread.
struct FnnWorkspace {
  std::vector<Eigen::VectorXd> a;  ///< a_0..a_{L-1} activations (a_0 = normalised input)
  Eigen::VectorXd z;               ///< normalised output, n_L
  std::vector<Eigen::MatrixXd> m;  ///< d a_l / d x (n_l x n_0) for the input Jacobian, l = 1..L-1
};

/// Scratch memory for block evaluations of the parameter Jacobian (used by the trainers).
struct FnnBlockWorkspace {
  std::vector<Eigen::MatrixXd> a;  ///< a_0..a_{L-1}, n_l x B (column per sample)
  std::vector<Eigen::MatrixXd> d;  ///< back-propagated sensitivities, n_l x B
};

class Fnn {
 public:
  /// An empty network (num_layers() == 0); only assignment and Load make it usable.
  Fnn() = default;
  /// Network with layer sizes {n_0, ..., n_L} (L >= 1, every n_l >= 1), all parameters zero and
  /// identity normalisation (MinMaxMap(n_0), MinMaxMap(n_L)). Throws std::invalid_argument.
  explicit Fnn(const std::vector<int>& layer_sizes);
  /// Convenience: sizes {inputs, hidden..., outputs}.
  static Fnn WithHiddenLayers(int inputs, const std::vector<int>& hidden, int outputs);
  /// W of WithHiddenLayers(inputs, hidden, outputs), as a double (no int overflow, nothing
  /// allocated): to size a job before building the network.
  static double CountParameters(int inputs, const std::vector<int>& hidden, int outputs);

  // ---- shape ----
  /// Number of weight layers L (hidden layers + 1); 0 for an empty network.
  int num_layers() const { return static_cast<int>(W_.size()); }
  int num_hidden_layers() const { return num_layers() > 0 ? num_layers() - 1 : 0; }
  int num_inputs() const { return sizes_.empty() ? 0 : sizes_.front(); }
  int num_outputs() const { return sizes_.empty() ? 0 : sizes_.back(); }
  /// {n_0, ..., n_L}.
  const std::vector<int>& layer_sizes() const { return sizes_; }
  /// W = sum_l n_l (n_{l-1} + 1).
  int num_parameters() const { return num_parameters_; }
  /// Offset of W_l (l = 1..L) in the flat parameter vector; b_l follows at + n_l n_{l-1}.
  int parameter_offset(int l) const;
  /// e.g. "3-35-35-3 tansig/linear".
  std::string Describe() const;

  // ---- normalisation ----
  /// Fit both maps from data (X: #samples x n_0, Y: #samples x n_L, same #samples >= 1, finite).
  /// Throws std::invalid_argument on a shape mismatch or non-finite data.
  void FitNormalization(const Eigen::Ref<const Eigen::MatrixXd>& X,
                        const Eigen::Ref<const Eigen::MatrixXd>& Y);
  const MinMaxMap& input_map() const { return in_map_; }
  const MinMaxMap& output_map() const { return out_map_; }
  /// Throws std::invalid_argument if the size is not n_0 (resp. n_L).
  void set_input_map(const MinMaxMap& m);
  void set_output_map(const MinMaxMap& m);

  // ---- parameters ----
  /// Nguyen-Widrow initialisation from `seed` (see the file comment). Same seed, same numbers.
  void InitializeNguyenWidrow(std::uint64_t seed);
  /// The flat parameter vector (layout in the file comment).
  Eigen::VectorXd parameters() const;
  /// Set all parameters from the flat vector (size num_parameters(), checked by assert).
  void set_parameters(const Eigen::Ref<const Eigen::VectorXd>& w);
  /// W_l (n_l x n_{l-1}) and b_l (n_l) for l = 1..L.
  const Eigen::MatrixXd& weights(int l) const { return W_[l - 1]; }
  const Eigen::VectorXd& biases(int l) const { return b_[l - 1]; }

  // ---- evaluation (original units) ----
  /// y = f(x): x of length n_0, returns n_L values.
  Eigen::VectorXd Forward(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// y = f(x) into y (length n_L) using ws; no heap allocation once ws has this network's shape.
  void Forward(const Eigen::Ref<const Eigen::VectorXd>& x, FnnWorkspace& ws,
               Eigen::Ref<Eigen::VectorXd> y) const;
  /// Batch: X is #samples x n_0, returns #samples x n_L (row per sample).
  Eigen::MatrixXd ForwardBatch(const Eigen::Ref<const Eigen::MatrixXd>& X) const;

  /// Input Jacobian dy/dx (n_L x n_0) at x, through both normalisations.
  Eigen::MatrixXd InputJacobian(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  /// As above, also returning y (length n_L); J must be n_L x n_0. No allocation once ws is shaped.
  void InputJacobian(const Eigen::Ref<const Eigen::VectorXd>& x, FnnWorkspace& ws,
                     Eigen::Ref<Eigen::VectorXd> y, Eigen::Ref<Eigen::MatrixXd> J) const;
  /// Batch: X is #samples x n_0; returns (#samples n_L) x n_0, rows s n_L .. s n_L + n_L - 1
  /// holding dy/dx of sample s.
  Eigen::MatrixXd InputJacobianBatch(const Eigen::Ref<const Eigen::MatrixXd>& X) const;

  /// Parameter Jacobian dy/dw (n_L x #parameters) of the output in original units at x.
  Eigen::MatrixXd ParameterJacobian(const Eigen::Ref<const Eigen::VectorXd>& x) const;

  // ---- block kernels on the normalised scale (what the trainers use) ----
  /// Normalised forward pass of a block: U is n_0 x B normalised inputs (column per sample);
  /// Z (n_L x B) receives the normalised outputs.
  void ForwardNormalized(const Eigen::Ref<const Eigen::MatrixXd>& U, FnnBlockWorkspace& ws,
                         Eigen::Ref<Eigen::MatrixXd> Z) const;
  /// Normalised outputs Z (n_L x B) and the TRANSPOSED parameter Jacobian Jt (#parameters x
  /// (B n_L)) of a block: column s n_L + k of Jt is d z_k / d w for sample s. (Column-major Jt is
  /// the row-major residual Jacobian Ceres expects.)
  void ParameterJacobianNormalized(const Eigen::Ref<const Eigen::MatrixXd>& U,
                                   FnnBlockWorkspace& ws, Eigen::Ref<Eigen::MatrixXd> Z,
                                   Eigen::Ref<Eigen::MatrixXd> Jt) const;

  // ---- file I/O ("softkin-fnn v1", see the file comment) ----
  /// Write to `path`. Throws std::runtime_error if the network is empty or the file cannot be
  /// written.
  void Save(const std::string& path) const;
  /// Write to a stream.
  void Write(std::ostream& out) const;
  /// Read from `path`. Throws std::runtime_error naming the file, line and field on any problem.
  static Fnn Load(const std::string& path);
  /// Read from a stream; `source` names it in error messages.
  static Fnn Read(std::istream& in, const std::string& source);

 private:
  std::vector<int> sizes_;
  int num_parameters_ = 0;
  std::vector<Eigen::MatrixXd> W_;
  std::vector<Eigen::VectorXd> b_;
  MinMaxMap in_map_, out_map_;
};

}  // namespace softkin
