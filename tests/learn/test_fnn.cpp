// The FNN: Eq. 5.7, normalisation identities, Jacobians against finite differences, the parameter
// layout, Nguyen-Widrow init, and the softkin-fnn v1 file round trip and its rejection of corrupt
// files.
#include "softkin/learn/fnn.hpp"

#include "learn_test_util.hpp"

#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

namespace softkin {
namespace {

using test::NearMatrix;

TEST(Fnn, TansigIsEquation57) {
  for (double n : {-30.0, -3.0, -0.7, -1e-3, 0.0, 1e-3, 0.25, 1.0, 4.0, 30.0})
    EXPECT_NEAR(Tansig(n), std::tanh(n), 1e-15) << n;
  EXPECT_EQ(Tansig(0.0), 0.0);
  EXPECT_NEAR(Tansig(-0.5), -Tansig(0.5), 1e-16);
  // The network's vectorised form is the same function: a 1-1 network with unit weights is tansig.
  Fnn net({1, 1, 1});
  net.set_parameters(Eigen::Vector4d(1.0, 0.0, 1.0, 0.0));  // W1, b1, W2, b2
  for (double n : {-0.9, -0.3, 0.0, 0.2, 0.8})  // identity maps: inputs and outputs in [-1, 1]
    EXPECT_NEAR(net.Forward(Eigen::VectorXd::Constant(1, n))(0), std::tanh(n), 1e-15) << n;
}

TEST(MinMaxMap, FitMapsTheRangeToMinusOneOne) {
  Eigen::MatrixXd X(4, 3);
  X << 1, 5, 7,  //
      3, -5, 7,  //
      2, 0, 7,   //
      -1, 1, 7;
  const MinMaxMap m = MinMaxMap::Fit(X);
  EXPECT_TRUE(NearMatrix(m.xmin(), Eigen::Vector3d(-1, -5, 7), 0, 0));
  EXPECT_TRUE(NearMatrix(m.xmax(), Eigen::Vector3d(3, 5, 7), 0, 0));
  Eigen::VectorXd u(3);
  m.Apply(Eigen::Vector3d(-1, -5, 7), u);
  EXPECT_TRUE(NearMatrix(u, Eigen::Vector3d(-1, -1, 0), 0, 1e-15));  // constant row -> 0
  m.Apply(Eigen::Vector3d(3, 5, 9), u);
  EXPECT_TRUE(NearMatrix(u, Eigen::Vector3d(1, 1, 2), 0, 1e-15));  // constant row: unit gain
  EXPECT_TRUE(NearMatrix(m.gain(), Eigen::Vector3d(0.5, 0.2, 1.0), 0, 1e-15));
  // Reverse inverts Apply, also in the column form.
  Eigen::MatrixXd cols = X.transpose();
  m.ApplyColumns(cols);
  EXPECT_LE(cols.topRows(2).cwiseAbs().maxCoeff(), 1.0 + 1e-15);
  m.ReverseColumns(cols);
  EXPECT_TRUE(NearMatrix(cols, X.transpose(), 0, 1e-14));
}

TEST(MinMaxMap, RejectsBadRanges) {
  EXPECT_THROW(MinMaxMap(Eigen::Vector2d(0, 2), Eigen::Vector2d(1, 1)),
               std::invalid_argument);  // min > max
  EXPECT_THROW(MinMaxMap(Eigen::Vector2d(0, 0), Eigen::Vector3d(1, 1, 1)), std::invalid_argument);
  EXPECT_THROW(MinMaxMap::Fit(Eigen::MatrixXd(0, 2)), std::invalid_argument);
  Eigen::MatrixXd bad = Eigen::MatrixXd::Ones(3, 2);
  bad(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(MinMaxMap::Fit(bad), std::invalid_argument);
}

TEST(Fnn, ShapeAndParameterLayout) {
  Fnn net({3, 5, 4, 2});
  EXPECT_EQ(net.num_layers(), 3);
  EXPECT_EQ(net.num_hidden_layers(), 2);
  EXPECT_EQ(net.num_parameters(), 5 * 4 + 4 * 6 + 2 * 5);
  EXPECT_EQ(net.Describe(), "3-5-4-2 tansig/linear");
  EXPECT_EQ(net.parameter_offset(1), 0);
  EXPECT_EQ(net.parameter_offset(2), 20);
  EXPECT_EQ(net.parameter_offset(3), 44);
  Eigen::VectorXd w(net.num_parameters());
  for (int i = 0; i < w.size(); ++i) w(i) = 0.01 * i - 0.3;
  net.set_parameters(w);
  EXPECT_EQ(net.parameters(), w);
  // W_l(i, j) at offset_l + j n_l + i, b_l(i) after W_l.
  for (int l = 1; l <= 3; ++l) {
    const int off = net.parameter_offset(l);
    const Eigen::MatrixXd& W = net.weights(l);
    for (int j = 0; j < W.cols(); ++j)
      for (int i = 0; i < W.rows(); ++i)
        EXPECT_EQ(W(i, j), w(off + j * W.rows() + i)) << l << " " << i << " " << j;
    for (int i = 0; i < W.rows(); ++i) EXPECT_EQ(net.biases(l)(i), w(off + W.size() + i));
  }
  EXPECT_THROW(Fnn({3}), std::invalid_argument);
  EXPECT_THROW(Fnn({3, 0, 2}), std::invalid_argument);
  EXPECT_EQ(Fnn::WithHiddenLayers(3, {35, 35}, 3).layer_sizes(), (std::vector<int>{3, 35, 35, 3}));
}

TEST(Fnn, ForwardMatchesTheDefinitionAndTheBatch) {
  const Fnn net = test::RandomNetwork({3, 6, 5, 2}, 11);
  const Eigen::MatrixXd X = test::UniformSamples(7, 3, -2, 3, 12);
  const Eigen::MatrixXd Y = net.ForwardBatch(X);
  FnnWorkspace ws;
  Eigen::VectorXd y(2);
  for (int s = 0; s < X.rows(); ++s) {
    // By hand: normalise, two tansig layers, linear, denormalise.
    Eigen::VectorXd a(3);
    net.input_map().Apply(X.row(s).transpose(), a);
    for (int l = 1; l <= 2; ++l)
      a = (net.weights(l) * a + net.biases(l)).unaryExpr([](double v) { return Tansig(v); });
    Eigen::VectorXd z = net.weights(3) * a + net.biases(3), ref(2);
    net.output_map().Reverse(z, ref);
    net.Forward(X.row(s).transpose(), ws, y);
    EXPECT_TRUE(NearMatrix(y, ref, 1e-13, 1e-12)) << s;
    EXPECT_TRUE(NearMatrix(Y.row(s).transpose(), ref, 1e-13, 1e-12)) << s;
  }
}

TEST(Fnn, InputJacobianMatchesCentralDifferencesThroughTheNormalisation) {
  Fnn net({3, 7, 6, 4});
  // Input column 1 is constant in the fitting data (unit-gain row), outputs on different scales.
  Eigen::MatrixXd X = test::UniformSamples(30, 3, -2.0, 3.0, 3);
  X.col(1).setConstant(0.75);
  Eigen::MatrixXd Y = test::UniformSamples(30, 4, -1.0, 1.0, 4);
  Y.col(0) *= 100.0;
  Y.col(3) *= 1e-2;
  net.FitNormalization(X, Y);
  EXPECT_EQ(net.input_map().gain()(1), 1.0);
  net.InitializeNguyenWidrow(5);
  const auto f = [&](const Eigen::VectorXd& x) { return net.Forward(x); };
  const Eigen::MatrixXd Xq = test::UniformSamples(5, 3, -2.0, 3.0, 6);
  const Eigen::MatrixXd Jb = net.InputJacobianBatch(Xq);
  for (int s = 0; s < Xq.rows(); ++s) {
    const Eigen::VectorXd x = Xq.row(s).transpose();
    const Eigen::MatrixXd J = net.InputJacobian(x);
    const Eigen::MatrixXd Jfd = test::CentralDifferences(f, x, 1e-5);
    ASSERT_GT(J.cwiseAbs().col(1).maxCoeff(), 0.0);  // the constant row still has a derivative
    EXPECT_TRUE(NearMatrix(J, Jfd, 1e-6, 1e-9 * (1.0 + Jfd.cwiseAbs().maxCoeff())))
        << "sample " << s;
    EXPECT_TRUE(NearMatrix(Jb.middleRows(4 * s, 4), J, 0, 0)) << "sample " << s;
  }
}

TEST(Fnn, InputJacobianOfALinearNetworkIsItsScaledWeightMatrix) {
  Fnn net = test::RandomNetwork({2, 3}, 21);
  const Eigen::MatrixXd expected = net.output_map().gain().cwiseInverse().asDiagonal() *
                                   net.weights(1) * net.input_map().gain().asDiagonal();
  EXPECT_TRUE(NearMatrix(net.InputJacobian(Eigen::Vector2d(0.3, -1.0)), expected, 1e-14, 0));
}

TEST(Fnn, ParameterJacobianMatchesCentralDifferences) {
  const Fnn net = test::RandomNetwork({2, 5, 4, 3}, 31);
  const Eigen::Vector2d x(0.4, 2.2);
  const auto f = [&](const Eigen::VectorXd& w) {
    Fnn copy = net;
    copy.set_parameters(w);
    return copy.Forward(x);
  };
  const Eigen::MatrixXd J = net.ParameterJacobian(x);
  const Eigen::MatrixXd Jfd = test::CentralDifferences(f, net.parameters(), 1e-6);
  ASSERT_EQ(J.cols(), net.num_parameters());
  EXPECT_TRUE(NearMatrix(J, Jfd, 1e-6, 1e-7 * (1.0 + Jfd.cwiseAbs().maxCoeff())));
}

TEST(Fnn, BlockParameterJacobianIsThePerSampleOneOnTheNormalisedScale) {
  const Fnn net = test::RandomNetwork({3, 4, 2}, 41);
  const Eigen::MatrixXd X = test::UniformSamples(5, 3, -2, 3, 42);
  Eigen::MatrixXd U = X.transpose();
  net.input_map().ApplyColumns(U);
  Eigen::MatrixXd Z(2, 5), Jt(net.num_parameters(), 10);
  FnnBlockWorkspace ws;
  net.ParameterJacobianNormalized(U, ws, Z, Jt);
  Eigen::MatrixXd Y = Z;
  net.output_map().ReverseColumns(Y);
  EXPECT_TRUE(NearMatrix(Y.transpose(), net.ForwardBatch(X), 1e-14, 1e-12));
  for (int s = 0; s < 5; ++s) {
    const Eigen::MatrixXd J = net.ParameterJacobian(X.row(s).transpose());  // original units
    const Eigen::MatrixXd Jn = net.output_map().gain().asDiagonal() * J;
    EXPECT_TRUE(NearMatrix(Jt.middleCols(2 * s, 2).transpose(), Jn, 1e-13, 1e-14)) << s;
  }
}

TEST(Fnn, NguyenWidrowIsSeededAndScaled) {
  Fnn a({3, 35, 35, 3}), b({3, 35, 35, 3}), c({3, 35, 35, 3});
  a.InitializeNguyenWidrow(7);
  b.InitializeNguyenWidrow(7);
  c.InitializeNguyenWidrow(8);
  EXPECT_EQ(a.parameters(), b.parameters());
  EXPECT_GT((a.parameters() - c.parameters()).norm(), 1.0);
  for (int l = 1; l <= 2; ++l) {
    const double beta = 0.7 * std::pow(35.0, 1.0 / a.layer_sizes()[l - 1]);
    for (int i = 0; i < 35; ++i)
      EXPECT_NEAR(a.weights(l).row(i).norm(), beta, 1e-12) << l << " " << i;
    EXPECT_LE(a.biases(l).cwiseAbs().maxCoeff(), beta);
  }
  EXPECT_LE(a.weights(3).cwiseAbs().maxCoeff(), 1.0 / std::sqrt(35.0));
  EXPECT_EQ(a.biases(3).norm(), 0.0);
}

// ---- file format ----

bool BitwiseEqual(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

TEST(FnnFile, RoundTripIsBitwiseExact) {
  test::TempDir dir;
  Fnn net({3, 6, 5, 2});
  Eigen::MatrixXd X = test::UniformSamples(40, 3, -2, 3, 51);
  X.col(2).setConstant(1.0 / 3.0);
  net.FitNormalization(X, test::UniformSamples(40, 2, -1e3, 1e-3, 52));
  net.InitializeNguyenWidrow(53);
  const std::string path = dir.file("net.fnn");
  net.Save(path);
  const Fnn back = Fnn::Load(path);
  EXPECT_EQ(back.layer_sizes(), net.layer_sizes());
  EXPECT_TRUE(BitwiseEqual(back.parameters(), net.parameters()));
  EXPECT_TRUE(BitwiseEqual(back.input_map().xmin(), net.input_map().xmin()));
  EXPECT_TRUE(BitwiseEqual(back.output_map().xmax(), net.output_map().xmax()));
  const Eigen::MatrixXd Xq = test::UniformSamples(9, 3, -3, 4, 54);
  EXPECT_TRUE(BitwiseEqual(back.ForwardBatch(Xq), net.ForwardBatch(Xq)));
  EXPECT_TRUE(BitwiseEqual(back.InputJacobianBatch(Xq), net.InputJacobianBatch(Xq)));
  // Saving the loaded network gives the same file.
  std::ostringstream s1, s2;
  net.Write(s1);
  back.Write(s2);
  EXPECT_EQ(s1.str(), s2.str());
}

class CorruptFnnFile : public ::testing::Test {
 protected:
  void SetUp() override {
    Fnn net = test::RandomNetwork({2, 3, 1}, 61);
    std::ostringstream s;
    net.Write(s);
    text_ = s.str();
  }
  // Writes `text` to a file, loads it and returns the error message ("" if it loaded).
  std::string LoadError(const std::string& text) {
    path_ = dir_.file("bad.fnn");
    std::ofstream(path_) << text;
    try {
      Fnn::Load(path_);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }
  std::string Replace(const std::string& from, const std::string& to) const {
    std::string t = text_;
    const std::size_t at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? t : t.replace(at, from.size(), to);
  }
  void ExpectRejected(const std::string& text, const std::string& field) {
    const std::string msg = LoadError(text);
    ASSERT_FALSE(msg.empty()) << "accepted a corrupt file (" << field << ")";
    EXPECT_NE(msg.find(path_), std::string::npos) << msg;
    EXPECT_NE(msg.find(field), std::string::npos) << msg;
  }
  test::TempDir dir_;
  std::string path_;
  std::string text_;
};

TEST_F(CorruptFnnFile, TheIntactTextLoads) { EXPECT_EQ(LoadError(text_), ""); }

TEST_F(CorruptFnnFile, WrongMagicOrVersion) {
  ExpectRejected(Replace("softkin-fnn", "softkin-net"), "magic");
  ExpectRejected(Replace("softkin-fnn v1", "softkin-fnn v2"), "version");
  ExpectRejected("", "magic");
}

TEST_F(CorruptFnnFile, Truncated) {
  const std::size_t at = text_.find("parameters");
  ExpectRejected(text_.substr(0, at + 40), "parameters[");
  ExpectRejected(Replace("end\n", ""), "end");
  ExpectRejected(text_.substr(0, text_.find("output_max")), "output_max");
}

TEST_F(CorruptFnnFile, WrongShapes) {
  ExpectRejected(Replace("sizes 2 3 1", "sizes 2 4 1"), "parameters");  // count no longer matches
  ExpectRejected(Replace("layers 3", "layers 4"), "sizes");
  ExpectRejected(Replace("sizes 2 3 1", "sizes 2 0 1"), "sizes[1]");
  ExpectRejected(Replace("parameters 13", "parameters 12"), "parameters");
  const std::size_t at = text_.find("input_min");
  const std::size_t eol = text_.find('\n', at);
  ExpectRejected(text_.substr(0, eol) + " 0.5" + text_.substr(eol),
                 "input_min");  // one value too many
}

TEST_F(CorruptFnnFile, NonFiniteOrInconsistentNumbers) {
  const std::size_t at = text_.find("parameters 13\n") + 14;
  const std::size_t eol = text_.find('\n', at);
  ExpectRejected(text_.substr(0, at) + "nan" + text_.substr(eol), "parameters[0]");
  ExpectRejected(text_.substr(0, at) + "inf" + text_.substr(eol), "parameters[0]");
  ExpectRejected(text_.substr(0, at) + "0.5x" + text_.substr(eol), "parameters[0]");
  // input_max below input_min.
  const std::size_t mx = text_.find("input_max");
  const std::size_t mx_eol = text_.find('\n', mx);
  ExpectRejected(text_.substr(0, mx) + "input_max -1e9 -1e9" + text_.substr(mx_eol),
                 "input_max[0]");
}

TEST(FnnFileErrors, MissingFileIsNamed) {
  try {
    Fnn::Load("/nonexistent/dir/net.fnn");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/net.fnn"), std::string::npos);
  }
  EXPECT_THROW(Fnn().Save("/tmp/never_written.fnn"), std::runtime_error);  // empty network
}

}  // namespace
}  // namespace softkin
