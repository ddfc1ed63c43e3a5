// Collision response by spring elements (solver/collision/collision_response.hpp,
// spring_system.hpp; thesis Sec. 3.2.3, Eq. 3.5, 3.8, 3.9): the spring system solves A_ff + K
// exactly after any sequence of updates and downdates; the spring energy, its gradient and the
// global system agree (finite differences); a pressed-in state fails the exact collision check
// without response and passes with it, for self-collision and for an obstacle.
#include "softkin/solver/collision/collision_response.hpp"

#include "softkin/solver/factory/fk_factory.hpp"
#include "softkin/solver/fk/fk_solver.hpp"
#include "softkin/solver/fk/energy.hpp"
#include "softkin/solver/mesh/mesh_gen.hpp"
#include "softkin/solver/robots/robots.hpp"

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <random>

namespace softkin {
namespace {

constexpr double kH = 2.0;  // cell size, mm

/// Two 4 x 4 x 2-cell blocks stacked in z with a one-cell air gap (z in [0, 4] and [6, 10]). The
/// lower block's bottom is fixed; the "press" displacement actuator moves the upper block's top
/// face along -z (range [0, 6] mm), so values above 2 mm push it into the lower block.
Scene TwoBlocks() {
  Scene s;
  s.name = "two_blocks";
  s.mesh = VoxelTetMesh(
      Eigen::Vector3d::Zero(), kH, Eigen::Vector3i(4, 4, 5),
      [](const Eigen::Vector3d&, const Eigen::Vector3i& c) { return c[2] == 2 ? -1 : 0; });
  s.body[0] = Material{"body", 0.5, 1.0};
  s.fixed = VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 1e-9);
  Actuator press;
  press.name = "press";
  press.type = ActuatorType::Displacement;
  press.vertices =
      VerticesOnPlane(s.mesh, Eigen::Vector3d(0, 0, 10), Eigen::Vector3d::UnitZ(), 1e-9);
  press.axis = -Eigen::Vector3d::UnitZ();
  press.rest = press.min = 0.0;
  press.max = 6.0;
  s.actuators.push_back(press);
  s.markers.push_back({"top", press.vertices});
  s.validate();
  return s;
}

/// Reference for SpringSystem: (A_ff + k sum_s c_s c_s^T) y = b assembled entry by entry and
/// solved by Eigen's own LDL^T, axis by axis. Empty if a factorisation fails.
Eigen::VectorXd DirectSolve(const Model& model, const std::vector<SpringStencil>& springs, double k,
                            const Eigen::VectorXd& b) {
  Eigen::VectorXd y(model.num_free_dofs());
  for (int d = 0; d < 3; ++d) {
    const std::vector<int>& fi = model.free_index(d);
    Eigen::SparseMatrix<double> M = model.A_ff(d);
    for (const auto& sp : springs)
      for (int a = 0; a < 4; ++a)
        for (int c = 0; c < 4; ++c) {
          if (sp.vertex[a] < 0 || sp.vertex[c] < 0) continue;
          const int i = fi[sp.vertex[a]], j = fi[sp.vertex[c]];
          if (i >= 0 && j >= 0) M.coeffRef(i, j) += k * sp.coef[a] * sp.coef[c];
        }
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(M);
    if (ldlt.info() != Eigen::Success) return Eigen::VectorXd();
    const int off = model.free_offset(d), n = model.free_offset(d + 1) - off;
    y.segment(off, n) = ldlt.solve(b.segment(off, n));
  }
  return y;
}

/// Both systems (update/downdate and refactorisation, holding the same springs) solve b as the
/// direct LDL^T of A_ff + K does, to 1e-9, and multiply their answers back to b.
void ExpectBothMatchADirectSolve(const Model& model, const SpringSystem& updown,
                                 const SpringSystem& refactor, double k, const Eigen::VectorXd& b,
                                 int round) {
  const Eigen::VectorXd ref = DirectSolve(model, updown.springs(), k, b);
  ASSERT_EQ(ref.size(), b.size());
  const Eigen::VectorXd y1 = updown.Solve(b), y2 = refactor.Solve(b);
  EXPECT_LT((y1 - ref).norm(), 1e-9 * ref.norm()) << "round " << round;
  EXPECT_LT((y2 - ref).norm(), 1e-9 * ref.norm()) << "round " << round;
  EXPECT_LT((updown.Multiply(y1) - b).norm(), 1e-9 * b.norm()) << "round " << round;
  EXPECT_LT((refactor.Multiply(y2) - b).norm(), 1e-9 * b.norm()) << "round " << round;
}

TEST(SpringSystem, UpdateDowndateMatchesADirectSolve) {
  const Scene scene = MakeRobot("pneumatic_finger", 5);
  const Model model(scene);
  SpringSystem updown(model), refactor(model, SpringSystem::Method::kRefactor);
  updown.set_refactor_after(0);  // never refactor: every change is an update/downdate
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> vert(0, model.num_vertices() - 1);
  const double k = 3.0 * model.A().diagonal().mean();
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(model.num_free_dofs(), -1.0, 2.0);
  std::vector<int> set;
  for (int round = 0; round < 6; ++round) {
    // Keep about half, add a few new ones: both updates and downdates.
    std::vector<int> next;
    for (int v : set)
      if (rng() % 2) next.push_back(v);
    for (int q = 0; q < 5; ++q) next.push_back(vert(rng));
    set = next;
    EXPECT_TRUE(updown.SetSprings(set, k) || set.empty());
    refactor.SetSprings(set, k);
    ExpectBothMatchADirectSolve(model, updown, refactor, k, b, round);
  }
  EXPECT_GT(updown.stats().columns_updated, 0);
  EXPECT_EQ(updown.stats().refactors, 0);
  EXPECT_GT(refactor.stats().refactors, 0);
  EXPECT_FALSE(updown.SetSprings(updown.springs(), k));  // same set: nothing to do
  EXPECT_THROW(updown.SetSprings(std::vector<int>{1}, 0.0), std::invalid_argument);
}

// Vertex-face springs couple a vertex with three others (off the diagonal of A_ff): update and
// downdate of such columns, and a refactorisation (which must analyse A_ff + K afresh, its
// pattern no longer A's), both match a direct solve.
TEST(SpringSystem, VertexFaceSpringsMatchADirectSolve) {
  const Scene scene = MakeRobot("pneumatic_finger", 5);
  const Model model(scene);
  SpringSystem updown(model), refactor(model, SpringSystem::Method::kRefactor);
  updown.set_refactor_after(0);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> vert(0, model.num_vertices() - 1);
  std::uniform_real_distribution<double> unit(0.05, 1.0);
  const double k = 3.0 * model.A().diagonal().mean();
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(model.num_free_dofs(), -1.0, 2.0);
  std::vector<SpringStencil> set;
  for (int round = 0; round < 6; ++round) {
    std::vector<SpringStencil> next;
    for (const auto& s : set)
      if (rng() % 2) next.push_back(s);
    for (int q = 0; q < 5; ++q) {
      // Any four distinct vertices (the pairs are far apart in the mesh, so K adds fill).
      std::array<int, 4> v;
      for (int j = 0; j < 4; ++j) {
        bool again;
        do {
          v[j] = vert(rng);
          again = std::find(v.begin(), v.begin() + j, v[j]) != v.begin() + j;
        } while (again);
      }
      Eigen::Vector3d w(unit(rng), unit(rng), unit(rng));
      w /= w.sum();
      next.push_back(q == 4 ? SpringStencil::Unit(v[0])
                            : SpringStencil::VertexFace(v[0], {v[1], v[2], v[3]}, w));
    }
    set = next;
    EXPECT_TRUE(updown.SetSprings(set, k));
    refactor.SetSprings(set, k);
    ExpectBothMatchADirectSolve(model, updown, refactor, k, b, round);
  }
  EXPECT_EQ(updown.stats().refactors, 0);
  // A refactorisation of the update/downdate system lands on the same solution.
  const Eigen::VectorXd before = updown.Solve(b);
  updown.Refactor();
  EXPECT_LT((updown.Solve(b) - before).norm(), 1e-9 * before.norm());
  std::vector<SpringStencil> bad = {SpringStencil::Unit(model.num_vertices())};
  EXPECT_THROW(updown.SetSprings(bad, k), std::invalid_argument);
}

TEST(CollisionResponse, SpringEnergyGradientMatchesFiniteDifferences) {
  for (const char* kind : {"target", "pair"}) {
    SCOPED_TRACE(kind);
    const bool pair = std::string(kind) == "pair";
    Scene scene = TwoBlocks();
    scene.solver.collision.self = true;
    scene.solver.collision.self_spring = SelfSpringFromString(kind);
    const Model model(scene);
    CollisionResponse resp(model, scene.solver.collision);
    // Push the upper block 3 mm down rigidly: its bottom layer enters the lower block.
    Eigen::MatrixX3d X = model.rest_positions();
    for (int v = 0; v < X.rows(); ++v)
      if (X(v, 2) > 5.0) X(v, 2) -= 3.0;
    EXPECT_TRUE(resp.Update(X));
    ASSERT_FALSE(resp.springs().empty());
    std::vector<char> involved(X.rows(), 0);
    for (const auto& s : resp.springs()) {
      EXPECT_EQ(s.kind, CollisionSpring::Kind::Self);
      EXPECT_GT(s.depth, 0.0);
      EXPECT_EQ(s.pair(), pair);
      involved[s.vertex] = 1;
      if (s.pair()) {
        for (int f : s.face) involved[f] = 1;
        EXPECT_NEAR(s.weights.sum(), 1.0, 1e-12);
        EXPECT_GE(s.weights.minCoeff(), 0.0);
        // At detection the target is where it would be as a fixed point: the exit plus eps.
        EXPECT_LT((s.TargetAt(X) - s.target).norm(), 1e-12);
      }
    }
    // Move off the targets, so the gradient is not zero.
    Eigen::MatrixX3d Y = X;
    for (int v = 0; v < Y.rows(); ++v)
      Y.row(v) += 0.1 * Eigen::RowVector3d(std::sin(v), std::cos(v), 0.3);
    // Analytic: dE_col/dx_free = 2 (K x - rhs) = 2 (AddSpringProduct - AddToRhs).
    Eigen::VectorXd Kx = Eigen::VectorXd::Zero(model.num_free_dofs()), Kt = Kx;
    Eigen::VectorXd yf;
    model.GatherFree(Y, &yf);
    resp.AddSpringProduct(yf, &Kx);
    resp.AddToRhs(Y, &Kt);
    const Eigen::VectorXd grad = 2.0 * (Kx - Kt);
    const double h = 1e-6;
    double worst = 0, scale = grad.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    int checked = 0;
    for (int v = 0; v < Y.rows(); ++v) {
      if (!involved[v]) continue;
      for (int d = 0; d < 3; ++d) {
        const int i = model.free_index(d)[v];
        if (i < 0) continue;
        Eigen::MatrixX3d P = Y, M = Y;
        P(v, d) += h;
        M(v, d) -= h;
        const double fd = (resp.Energy(P) - resp.Energy(M)) / (2 * h);
        worst = std::max(worst, std::abs(fd - grad[model.free_offset(d) + i]));
        total[d] += grad[model.free_offset(d) + i];
        ++checked;
      }
    }
    EXPECT_GT(checked, 0);
    EXPECT_LT(worst, 1e-6 * scale);
    // A vertex-face spring's forces on v and on the face cancel (action and reaction): the
    // gradient sums to zero over the free vertices (none of these is prescribed). A fixed target
    // takes the reaction out of the system.
    if (pair)
      EXPECT_LT(total.norm(), 1e-9 * scale);
    else
      EXPECT_GT(total.norm(), 0.1 * scale);
    // Vertices no spring involves have no spring gradient.
    int zero = 0;
    for (int v = 0; v < Y.rows(); ++v) {
      const int i = model.free_index(0)[v];
      if (i < 0 || involved[v]) continue;
      EXPECT_EQ(grad[i], 0.0);
      ++zero;
    }
    EXPECT_GT(zero, 0);
  }
}

TEST(CollisionResponse, TargetsLieOutsideTheCollidedBlock) {
  Scene scene = TwoBlocks();
  scene.solver.collision.self = true;
  // The fixed targets of Eq. 3.5 (half way out, plus eps), whose points this test checks.
  scene.solver.collision.self_spring = SelfSpring::kTarget;
  scene.solver.collision.epsilon = 0.1;
  const Model model(scene);
  CollisionResponse resp(model, scene.solver.collision);
  Eigen::MatrixX3d X = model.rest_positions();
  for (int v = 0; v < X.rows(); ++v)
    if (X(v, 2) > 5.0) X(v, 2) -= 3.0;  // upper block bottom (z = 6) now at z = 3, inside
  resp.Update(X);
  int upper = 0, lower = 0;
  for (const auto& s : resp.springs()) {
    // Vertices on the blocks' side faces have slanted normals; check the faces' interiors.
    const Eigen::Vector3d r = model.rest_positions().row(s.vertex);
    if (r.x() < 1e-9 || r.x() > 8 - 1e-9 || r.y() < 1e-9 || r.y() > 8 - 1e-9) continue;
    if (r.z() > 5.0) {
      // A vertex of the upper block (at z = 3) inside the lower one: pulled up along its
      // -n = +z by half the overlap to the lower block's top face z = 4 (the other side takes
      // the other half), plus eps.
      ++upper;
      EXPECT_NEAR(s.target.z(), 3.0 + 0.5 + 0.1, 1e-9);
      EXPECT_NEAR(s.normal.z(), 1.0, 1e-9);
      EXPECT_NEAR(s.depth, 1.0, 1e-9);
    } else {
      // A lower-block vertex (at z = 4) inside the upper block: pushed down towards its bottom
      // z = 3, half way, plus eps.
      ++lower;
      EXPECT_NEAR(s.target.z(), 4.0 - 0.5 - 0.1, 1e-9);
      EXPECT_NEAR(s.normal.z(), -1.0, 1e-9);
    }
  }
  EXPECT_EQ(upper, 9);  // the 3 x 3 interior vertices of each face
  EXPECT_EQ(lower, 9);
  const CollisionCheck check = resp.Check(X);
  EXPECT_FALSE(check.collision_free());
  EXPECT_NEAR(check.max_penetration, 1.0, 1e-9);
  EXPECT_NEAR(check.self_penetration, 1.0, 1e-9);  // the depth split by kind
  EXPECT_EQ(check.obstacle_contacts, 0);
  EXPECT_EQ(check.obstacle_penetration, 0.0);
  // Two intact blocks overlapping: contacts between separate parts, no tangle.
  EXPECT_EQ(check.inverted_elements, 0);
  EXPECT_EQ(check.tangled_contacts, 0);
  EXPECT_TRUE(resp.Check(model.rest_positions()).collision_free());
}

// A fold of one block through itself (the top-face vertex over the block's centre pushed 3 mm
// down, through its 2 mm top layer): the check counts the inverted elements as
// CountInvertedElements does, finds the fold's self contacts, and attributes every one of them to
// the tangle. The rest shape has neither.
TEST(CollisionResponse, CheckSeparatesTanglesFromContacts) {
  Scene scene = TwoBlocks();
  scene.solver.collision.self = true;
  const Model model(scene);
  CollisionResponse resp(model, scene.solver.collision);
  const CollisionCheck rest = resp.Check(model.rest_positions());
  EXPECT_EQ(rest.inverted_elements, 0);
  EXPECT_EQ(rest.tangled_contacts, 0);
  EXPECT_EQ(rest.self_contacts, 0);

  Eigen::MatrixX3d X = model.rest_positions();
  int top = -1;
  for (int v = 0; v < X.rows(); ++v)
    if ((X.row(v) - Eigen::RowVector3d(4, 4, 10)).norm() < 1e-9) top = v;
  ASSERT_GE(top, 0);
  X(top, 2) = 7.0;
  const CollisionCheck fold = resp.Check(X);
  EXPECT_EQ(fold.inverted_elements, CountInvertedElements(model.mesh(), X));
  EXPECT_GT(fold.inverted_elements, 0);
  EXPECT_EQ(fold.inverted_body_elements, fold.inverted_elements);  // TwoBlocks is all body
  EXPECT_GE(fold.self_contacts, 1);
  EXPECT_EQ(fold.tangled_contacts, fold.self_contacts);
  EXPECT_FALSE(fold.collision_free());

  // The same fold when the upper block is a pneumatic chamber: its inverted elements are not
  // body elements.
  Scene chamber = scene;
  for (auto& e : chamber.mesh.elements)
    if (chamber.mesh.vertices.row(e.v[0]).z() > 5.0) e.region = 1;
  Actuator gas;
  gas.name = "gas";
  gas.regions = {1};
  chamber.actuators.push_back(gas);
  chamber.validate();
  const Model chamber_model(chamber);
  CollisionResponse chamber_resp(chamber_model, chamber.solver.collision);
  const CollisionCheck gas_fold = chamber_resp.Check(X);
  EXPECT_EQ(gas_fold.inverted_elements, fold.inverted_elements);
  EXPECT_EQ(gas_fold.inverted_body_elements, 0);
}

// Between two bodies of one mesh ("auto"), a vertex goes to the closest point of the other body's
// surface; "walk" sends it along -n(v) (the thesis's rule). They agree on a face's interior and
// differ at a corner, whose -n(v) is slanted: the upper block pushed 3 mm down and 1.5 mm along x
// and y puts its bottom corner (rest (0, 0, 6)) at (1.5, 1.5, 3), 1 mm below the lower block's top
// face and 1.5 mm from its sides. Its -n(v), about (1, 1, 1) / sqrt(3), leaves through the top
// face about sqrt(3) mm away.
TEST(CollisionResponse, BetweenBodiesTheTargetIsTheClosestSurfacePoint) {
  Scene scene = TwoBlocks();
  scene.solver.collision.self = true;
  // The fixed targets of Eq. 3.5 (half way out, plus eps), whose points this test checks.
  scene.solver.collision.self_spring = SelfSpring::kTarget;
  scene.solver.collision.epsilon = 0.1;
  const Model model(scene);
  Eigen::MatrixX3d X = model.rest_positions();
  int corner = -1;
  for (int v = 0; v < X.rows(); ++v) {
    if (X(v, 2) < 5.0) continue;
    if (X.row(v).norm() == 6.0) corner = v;  // (0, 0, 6)
    X.row(v) += Eigen::RowVector3d(1.5, 1.5, -3.0);
  }
  ASSERT_GE(corner, 0);
  for (const char* rule : {"auto", "walk"}) {
    CollisionOptions o = scene.solver.collision;
    o.self_target = SelfTargetFromString(rule);
    CollisionResponse resp(model, o);
    EXPECT_EQ(resp.num_bodies(), 2);
    EXPECT_NE(resp.body(corner), resp.body(0));
    resp.Update(X);
    const auto& sp = resp.springs();
    const auto it = std::find_if(sp.begin(), sp.end(),
                                 [&](const CollisionSpring& s) { return s.vertex == corner; });
    ASSERT_NE(it, sp.end()) << rule;
    if (std::string(rule) == "auto") {
      EXPECT_NEAR(it->depth, 1.0, 1e-9);
      EXPECT_NEAR((it->normal - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-9);
      EXPECT_NEAR((it->target - Eigen::Vector3d(1.5, 1.5, 3.0 + 0.5 + 0.1)).norm(), 0.0, 1e-9);
    } else {
      // Along the slanted -n(v) (about (1, 1, 1) / sqrt(3); its exact tilt depends on the
      // corner's triangles), the exit through the top face lies further.
      const Eigen::Vector3d m = -resp.VertexNormal(X, corner);
      ASSERT_GT(m.z(), 0.3);
      EXPECT_NEAR(it->depth, 1.0 / m.z(), 1e-9);
      EXPECT_GT(it->depth, 1.2);
    }
    // Every upper-block vertex inside the lower block lies on the upper block's bottom face, 1 mm
    // below the lower block's top face. With "auto" that face is its exit: the lower block's side
    // faces x = 8 and y = 8, 0.5 mm from some of them, face sideways, not against the bottom
    // face's normal -z. The walk never exits closer.
    int upper = 0;
    for (const auto& s : sp) {
      if (model.rest_positions()(s.vertex, 2) < 5.0) continue;
      ++upper;
      if (std::string(rule) == "auto")
        EXPECT_NEAR(s.depth, 1.0, 1e-9) << "vertex " << s.vertex;
      else
        EXPECT_GE(s.depth, 1.0 - 1e-9) << "vertex " << s.vertex;
    }
    EXPECT_EQ(upper, 16);  // (x, y) in {1.5, 3.5, 5.5, 7.5}^2
    // The exact check measures the penetration as the distance to the other body's surface.
    EXPECT_NEAR(resp.Check(X).max_penetration, 1.0, 1e-9);
  }
}

TEST(CollisionResponse, PressedBlocksAreCollisionFreeOnlyWithResponse) {
  Scene scene = TwoBlocks();
  Eigen::VectorXd c(1);
  c << 4.0;  // the upper block's top moves 4 mm down: 2 mm more than the gap
  // Without response the upper block simply passes into the lower one.
  {
    auto model = std::make_shared<const Model>(scene);
    auto solver = MakeFkSolver(model, scene.solver);
    const FkResult r = solver->Solve(c);
    ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
    EXPECT_FALSE(r.collision_active);
    Scene checked = scene;
    checked.solver.collision.self = true;
    const Model m2(checked);
    CollisionResponse probe(m2, checked.solver.collision);
    const CollisionCheck check = probe.Check(r.positions);
    EXPECT_GT(check.self_contacts, 0);
    EXPECT_GT(check.max_penetration, 1.0);
  }
  for (const char* variant : {"updown", "refactor", "auto", "pair", "pair-auto"}) {
    SCOPED_TRACE(variant);
    scene.solver.collision.self = true;
    // "auto": the closest point of the other block's surface as the exit; "pair": vertex-face
    // springs (both with update/downdate).
    const std::string v = variant;
    const bool between = v == "auto" || v == "pair-auto";
    const bool pair = v == "pair" || v == "pair-auto";
    scene.solver.collision.self_target = between ? SelfTarget::kAuto : SelfTarget::kWalk;
    scene.solver.collision.self_spring = pair ? SelfSpring::kPair : SelfSpring::kTarget;
    const char* update = (between || pair) ? "updown" : variant;
    scene.solver.continuation_steps = 4;  // progressive, as Algorithm 2: 1 mm per step
    scene.solver.collision.update = SpringUpdateFromString(update);
    auto model = std::make_shared<const Model>(scene);
    auto solver = MakeFkSolver(model, scene.solver);
    const FkResult r = solver->Solve(c);
    ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
    EXPECT_TRUE(r.collision_active);
    EXPECT_TRUE(r.collision.collision_free()) << r.BriefReport();
    EXPECT_EQ(r.collision.max_penetration, 0.0);
    EXPECT_EQ(r.collision.self_contacts, 0);
    EXPECT_GT(r.collision_stats.springs_added, 0);
    EXPECT_GT(r.springs, 0);  // the blocks are pressed together: contact holds
    EXPECT_TRUE(r.positions.allFinite());
    // The blocks touch rather than bounce apart: across the middle of the contact, the upper
    // block's bottom face sits on the lower block's top face, a few eps above it.
    double upper_bottom = 0, lower_top = 0;
    int nu = 0, nl = 0;
    for (int v = 0; v < r.positions.rows(); ++v) {
      const Eigen::Vector3d p = model->rest_positions().row(v);
      if (p.x() < 3 || p.x() > 5 || p.y() < 3 || p.y() > 5) continue;  // the central vertices
      if (std::abs(p.z() - 6.0) < 1e-9) upper_bottom += r.positions(v, 2), ++nu;
      if (std::abs(p.z() - 4.0) < 1e-9) lower_top += r.positions(v, 2), ++nl;
    }
    ASSERT_GT(nu, 0);
    ASSERT_GT(nl, 0);
    const double gap = upper_bottom / nu - lower_top / nl;
    // Contact forces: the elastic reactions at the held top and the fixed bottom (the frozen-
    // target gradient of Algorithm 1's fixed point) and each block's mean compression over its
    // 5 x 5 contact face.
    Eigen::MatrixX3d g;
    FrozenTargetGradient(*model, r.positions, c, &g);
    double top = 0, bottom = 0, zu = 0, zl = 0;
    for (int q = 0; q < g.rows(); ++q) {
      const Eigen::Vector3d p = model->rest_positions().row(q);
      if (p.z() > 10 - 1e-9) top += g(q, 2);
      if (p.z() < 1e-9) bottom += g(q, 2);
      if (std::abs(p.z() - 6.0) < 1e-9) zu += r.positions(q, 2) / 25;
      if (std::abs(p.z() - 4.0) < 1e-9) zl += r.positions(q, 2) / 25;
    }
    EXPECT_LT(top, 0.0);     // the press pushes down on the upper block's top ...
    EXPECT_GT(bottom, 0.0);  // ... and the ground up on the lower block's bottom
    if (pair) {
      // Vertex-face springs pass the force on unchanged (action and reaction): the two
      // reactions balance, and two equal blocks in series share the 2 mm about equally (1.07
      // and 0.96 mm measured; the eps gap and the rims take the rest).
      EXPECT_LT(std::abs(top + bottom), 1e-3 * std::abs(top));
      const double upper_c = 4.0 - (6.0 - zu), lower_c = 4.0 - zl;
      EXPECT_GT(upper_c, 0.85);
      EXPECT_LT(upper_c, 1.15);
      EXPECT_GT(lower_c, 0.85);
      EXPECT_LT(lower_c, 1.15);
    }
    EXPECT_GT(gap, 0.0);
    EXPECT_LT(gap, 0.5);
    // The lower block is compressed by the contact (with the default "walk" rule). With fixed
    // targets not by half of the 2 mm, as two equal blocks in series would be: each side's
    // springs pull to fixed targets, so the forces on the two sides need not balance (0.24 mm at
    // the centre with "walk", 0.15 mm with "auto"; bottom reaction 70.1 against 37.9 at the top
    // with "walk"; docs/collision_response.md).
    if (!between && !pair) {
      EXPECT_LT(lower_top / nl, 4.0 - 0.2) << update;
    }
  }
}

/// A 4 x 4 x 2-cell block (x, y in [0, 8], z in [2, 6]) whose top face a displacement actuator
/// moves along `axis`, above a box obstacle (top face at z = 1) or, with `cylinder`, above a
/// cylinder lying along y (axis at x = 4, z = -9, radius 10: top at z = 1), so contact normals
/// are tilted.
Scene BlockOverObstacle(const Eigen::Vector3d& axis, bool cylinder) {
  Scene s;
  s.name = "block_over_obstacle";
  s.mesh = VoxelTetMesh(Eigen::Vector3d(0, 0, 2), kH, Eigen::Vector3i(4, 4, 2),
                        [](const Eigen::Vector3d&, const Eigen::Vector3i&) { return 0; });
  s.body[0] = Material{"body", 0.5, 1.0};
  Actuator press;
  press.name = "press";
  press.type = ActuatorType::Displacement;
  press.vertices =
      VerticesOnPlane(s.mesh, Eigen::Vector3d(0, 0, 6), Eigen::Vector3d::UnitZ(), 1e-9);
  press.axis = axis.normalized();
  press.rest = press.min = 0.0;
  press.max = 6.0;
  s.actuators.push_back(press);
  if (cylinder)
    s.obstacles.push_back(
        MakeCylinderSurface(Eigen::Vector3d(4, -10, -9), Eigen::Vector3d::UnitY(), 10.0, 28.0, 96));
  else
    s.obstacles.push_back(
        MakeBoxSurface(Eigen::Vector3d(-20, -20, -3), Eigen::Vector3d(30, 30, 1)));
  s.validate();
  return s;
}

// The PneuNet finger whose chamber walls press on each other across their slits (Fig. 3.10),
// inflated to a volume ratio of 2.5 in 4 warm-started steps, with the default self-contact
// response (vertex-face springs), the thesis's fixed targets, and none.
// - The default still bends: at least as far as without response (the walls pressing on each
//   other drive the bending, as in a PneuNet), where fixed targets freeze it. Measured at res 5:
//   the tip goes down 20.1 mm with the default, 11.1 mm without response, 1.8 mm with fixed
//   targets.
// - Its final state is collision-free by the exact check.
// - Its contact forces sum to zero: with no external load, the reactions at the clamped base then
//   sum to zero too (the elastic forces of each element do), which fixed targets violate
//   (|sum| / sum of norms: 3e-6 with the default, 0.63 with fixed targets).
TEST(CollisionResponse, SelfCollidingFingerBendsCollisionFreeWithBalancedForces) {
  struct Outcome {
    double tip_drop = 0;      // rest tip z minus final tip z, mm
    double reaction_sum = 0;  // |sum of the base's reactions| / sum of their norms
    bool collision_free = false;
  };
  const auto run = [](const char* variant) {
    Scene scene = MakeRobot("selfcollision_finger", 5, {});
    EXPECT_TRUE(scene.solver.collision.self);
    const std::string v = variant;
    if (v == "none") scene.solver.collision.self = false;
    if (v == "target") scene.solver.collision.self_spring = SelfSpring::kTarget;
    if (v == "default") {
      EXPECT_EQ(scene.solver.collision.self_spring, SelfSpring::kPair);
    }
    auto model = std::make_shared<const Model>(scene);
    auto solver = MakeFkSolver(model, scene.solver);
    const int tip = scene.marker_index("tip");
    if (tip < 0) {
      ADD_FAILURE() << "selfcollision_finger has no tip marker";
      return Outcome{};
    }
    FkResult r;
    Eigen::VectorXd c(1);
    for (int step = 1; step <= 4; ++step) {
      c << 1.0 + 1.5 * step / 4.0;
      r = solver->Solve(c, step > 1 ? &r.positions : nullptr);
      EXPECT_EQ(r.status, FkStatus::Converged) << v << " step " << step << ": " << r.BriefReport();
    }
    Outcome o;
    o.tip_drop = scene.marker_positions(model->rest_positions())(tip, 2) -
                 scene.marker_positions(r.positions)(tip, 2);
    // The exact check, also for the solve without response (which does not check itself).
    Scene checked = scene;
    checked.solver.collision.self = true;
    const Model probe_model(checked);
    o.collision_free = CollisionResponse(probe_model, checked.solver.collision)
                           .Check(r.positions)
                           .collision_free();
    Eigen::MatrixX3d g;
    FrozenTargetGradient(*model, r.positions, c, &g);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double norms = 0;
    for (int f : model->fixed_vertices()) {
      sum += g.row(f).transpose();
      norms += g.row(f).norm();
    }
    o.reaction_sum = sum.norm() / norms;
    std::printf(
        "  %-7s: tip down %.2f mm, collision-free %d, |sum of base reactions| / sum of "
        "norms %.2e (%d iterations, last step)\n",
        variant, o.tip_drop, o.collision_free, o.reaction_sum, r.iterations);
    return o;
  };
  const Outcome pair = run("default"), target = run("target"), none = run("none");
  EXPECT_TRUE(pair.collision_free);
  EXPECT_TRUE(target.collision_free);
  EXPECT_GT(pair.tip_drop, 0.95 * none.tip_drop);
  EXPECT_GT(pair.tip_drop, 2.0 * target.tip_drop);
  EXPECT_LT(pair.reaction_sum, 1e-3);
  EXPECT_GT(target.reaction_sum, 10 * pair.reaction_sum);
}

// From rest straight to alpha = 2, the first global step pushes the fingers' segments across
// their 0.2 mm slits before any contact check; the springs then pull the wrong way and the state
// tangles. lg-aa sees the tangle, restarts the stage with half the load step, and ends where an
// explicit two-stage continuation ends. (lg-aa by name: `auto` hands such a cold solve to newton.)
TEST(CollisionResponse, ColdSelfContactSolveCutsTheLoadStepBackWhenItTangles) {
  const Scene scene = MakeRobot("selfcollision_finger", 6, {});
  ASSERT_EQ(scene.solver.continuation_steps, 1);
  auto model = std::make_shared<const Model>(scene);
  Eigen::VectorXd c(1);
  c << 2.0;
  FkOptions lg = scene.solver;
  lg.solver = FkSolverType::kLgAa;
  const FkResult cold = MakeFkSolver(model, lg)->Solve(c);
  ASSERT_EQ(cold.status, FkStatus::Converged) << cold.BriefReport();
  EXPECT_NE(cold.message.find("cut the load step back 1 time(s)"), std::string::npos)
      << cold.message;
  EXPECT_TRUE(cold.collision.collision_free()) << cold.BriefReport();
  EXPECT_EQ(cold.inverted_elements, 0);
  FkOptions two = lg;
  two.continuation_steps = 2;
  const FkResult staged = MakeFkSolver(model, two)->Solve(c);
  ASSERT_EQ(staged.status, FkStatus::Converged) << staged.BriefReport();
  EXPECT_EQ(staged.message.find("cut the load step"), std::string::npos) << staged.message;
  // Same fixed point to the stopping rule (tolerance 1e-5 of the size per iteration).
  EXPECT_LT((cold.positions - staged.positions).rowwise().norm().maxCoeff(), 1e-3 * model->size());
  EXPECT_NEAR(cold.energy, staged.energy, 1e-4 * staged.energy);
}

TEST(CollisionResponse, BlockPressedIntoAnObstacleStaysOut) {
  // One block, its top face pressed 3 mm down onto a box obstacle under it. The moved top face is
  // held in every coordinate; nothing else is fixed.
  const Scene s = BlockOverObstacle(-Eigen::Vector3d::UnitZ(), false);
  Eigen::VectorXd c(1);
  c << 3.0;  // the bottom (z = 2) would reach z = -1 if it moved rigidly
  for (bool respond : {false, true}) {
    Scene t = s;
    t.solver.collision.obstacles = respond;
    t.validate();
    auto model = std::make_shared<const Model>(t);
    auto solver = MakeFkSolver(model, t.solver);
    const FkResult r = solver->Solve(c);
    ASSERT_NE(r.status, FkStatus::InvalidInput) << r.BriefReport();
    const double lowest = r.positions.col(2).minCoeff();
    if (respond) {
      ASSERT_EQ(r.status, FkStatus::Converged) << r.BriefReport();
      EXPECT_TRUE(r.collision.collision_free()) << r.BriefReport();
      EXPECT_GT(lowest, 1.0 - 1e-9);  // on the obstacle's top face, not through it
      EXPECT_GT(r.springs, 0);
    } else {
      EXPECT_LT(lowest, 0.0);  // passes through
      // The exact check still reports the obstacle (response off), with the depth as its own.
      // The box spans z in [-3, 1] and reaches at least 5 mm beyond the block's sides, so a vertex
      // inside it is min(1 - z, z + 3) deep. The check tests the block's surface vertices (rest x
      // or y at 0 or 8, or z at 2 or 6).
      CollisionResponse probe(*model, t.solver.collision);
      const CollisionCheck ck = probe.Check(r.positions);
      double deepest = 0;
      int inside = 0;
      for (int v = 0; v < r.positions.rows(); ++v) {
        const Eigen::Vector3d p0 = model->rest_positions().row(v);
        const bool surface = std::abs(p0.x()) < 1e-9 || std::abs(p0.x() - 8) < 1e-9 ||
                             std::abs(p0.y()) < 1e-9 || std::abs(p0.y() - 8) < 1e-9 ||
                             std::abs(p0.z() - 2) < 1e-9 || std::abs(p0.z() - 6) < 1e-9;
        const double z = r.positions(v, 2);
        if (!surface || z >= 1.0) continue;
        ++inside;
        deepest = std::max(deepest, std::min(1.0 - z, z + 3.0));
      }
      EXPECT_EQ(ck.obstacle_contacts, inside);
      EXPECT_GT(deepest, 1.5);
      EXPECT_NEAR(ck.obstacle_penetration, deepest, 1e-9);
      EXPECT_EQ(ck.self_contacts, 0);
      EXPECT_EQ(ck.self_penetration, 0.0);
      EXPECT_EQ(ck.max_penetration, ck.obstacle_penetration);
    }
  }
}

TEST(CollisionResponse, PlaneObstacleSpringsSolveTheCoupledSystem) {
  // The block pushed 3 mm down into the cylinder: contact normals have x and z parts, so each
  // plane spring's k n n^T couples a vertex's coordinates. The Woodbury solve must match a direct
  // solve of the assembled system, and the energy's gradient finite differences.
  Scene scene = BlockOverObstacle(-Eigen::Vector3d::UnitZ(), true);
  scene.solver.collision.obstacle_spring = ObstacleSpring::kPlane;
  const Model model(scene);
  CollisionResponse resp(model, scene.solver.collision);
  Eigen::VectorXd c(1);
  c << 3.0;
  Eigen::MatrixX3d X = model.rest_positions();
  X.col(2).array() -= 3.0;
  model.ApplyConstraints(c, &X);
  EXPECT_TRUE(resp.Update(X));
  ASSERT_GT(resp.num_plane_springs(), 4);
  double tilt = 0;
  for (const auto& s : resp.springs()) {
    EXPECT_EQ(s.kind, CollisionSpring::Kind::Obstacle);
    tilt = std::max(tilt, std::abs(s.normal.x()));
  }
  EXPECT_GT(tilt, 0.1);  // off-centre contacts have tilted normals
  const int nf = model.num_free_dofs();
  const double k = resp.stiffness();
  // Assemble A_ff (per axis block) + k sum_s u_s u_s^T, u_s = n_s on v_s's free coordinates.
  std::vector<Eigen::Triplet<double>> trip;
  for (int d = 0; d < 3; ++d) {
    const Eigen::SparseMatrix<double>& A = model.A_ff(d);
    for (int col = 0; col < A.outerSize(); ++col)
      for (Eigen::SparseMatrix<double>::InnerIterator it(A, col); it; ++it)
        trip.emplace_back(model.free_offset(d) + it.row(), model.free_offset(d) + it.col(),
                          it.value());
  }
  for (const auto& s : resp.springs())
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const int ia = model.free_index(a)[s.vertex], ib = model.free_index(b)[s.vertex];
        if (ia >= 0 && ib >= 0)
          trip.emplace_back(model.free_offset(a) + ia, model.free_offset(b) + ib,
                            k * s.normal[a] * s.normal[b]);
      }
  Eigen::SparseMatrix<double> M(nf, nf);
  M.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> direct(M);
  ASSERT_EQ(direct.info(), Eigen::Success);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  Eigen::VectorXd b(nf), x(nf);
  for (int i = 0; i < nf; ++i) b[i] = uni(rng), x[i] = uni(rng);
  const Eigen::VectorXd y_direct = direct.solve(b);
  EXPECT_LT((resp.Solve(b) - y_direct).norm(), 1e-9 * y_direct.norm());
  EXPECT_LT((resp.Multiply(x) - M * x).norm(), 1e-10 * (M * x).norm());
  // Without the coupling (axis by axis) the solve differs: the test sees the n n^T terms.
  EXPECT_GT((resp.system().Solve(b) - y_direct).norm(), 1e-3 * y_direct.norm());

  // Gradient of the spring energy against central differences, off the targets.
  Eigen::MatrixX3d Y = X;
  for (int v = 0; v < Y.rows(); ++v)
    Y.row(v) += 0.1 * Eigen::RowVector3d(std::sin(v), std::cos(v), 0.3);
  model.ApplyConstraints(c, &Y);
  Eigen::VectorXd Kx = Eigen::VectorXd::Zero(nf), Kt = Kx, yf;
  model.GatherFree(Y, &yf);
  resp.AddSpringProduct(yf, &Kx);
  resp.AddToRhs(Y, &Kt);
  const Eigen::VectorXd grad = 2.0 * (Kx - Kt);
  const double scale = grad.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0.0);
  double worst = 0;
  for (const auto& s : resp.springs()) {
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int d = 0; d < 3; ++d) {
      const int i = model.free_index(d)[s.vertex];
      ASSERT_GE(i, 0);
      const double h = 1e-6;
      Eigen::MatrixX3d P = Y, Q = Y;
      P(s.vertex, d) += h;
      Q(s.vertex, d) -= h;
      const double fd = (resp.Energy(P) - resp.Energy(Q)) / (2 * h);
      g[d] = grad[model.free_offset(d) + i];
      worst = std::max(worst, std::abs(fd - g[d]));
    }
    // Frictionless: the force on the vertex lies along the contact normal.
    EXPECT_LT(g.cross(s.normal).norm(), 1e-9 * scale);
  }
  EXPECT_LT(worst, 1e-6 * scale);
}

TEST(CollisionResponse, PlaneObstacleSpringsLetTheContactSlide) {
  // The block's top is moved 3 mm down and 3 mm along +x: its bottom meets the box obstacle and
  // must slide over it. At equilibrium a frictionless contact passes no tangential force, so the
  // held top face takes no x reaction. Point springs (Eq. 3.5, refreshed to the closest point at
  // each check) have the same fixed point but creep towards it: between checks they hold a vertex
  // where it is, so each check lets it slide only by its tangential force / k.
  Scene scene = BlockOverObstacle(Eigen::Vector3d(1, 0, -1), false);
  Eigen::VectorXd c(1);
  c << 3.0 * std::sqrt(2.0);
  auto solve = [&](const char* kind, int cap, Eigen::Vector3d* top) {
    Scene t = scene;
    t.solver.collision.obstacle_spring = ObstacleSpringFromString(kind);
    t.solver.max_iterations = cap;
    auto model = std::make_shared<const Model>(t);
    const FkResult r = MakeFkSolver(model, t.solver)->Solve(c);
    Eigen::MatrixX3d g;
    FrozenTargetGradient(*model, r.positions, c, &g);
    top->setZero();
    for (int q : t.actuators[0].vertices) *top += g.row(q).transpose();
    return r;
  };
  Eigen::Vector3d top_plane, top_point;
  const FkResult plane = solve("plane", 10000, &top_plane);
  ASSERT_EQ(plane.status, FkStatus::Converged) << plane.BriefReport();
  EXPECT_TRUE(plane.collision.collision_free()) << plane.BriefReport();
  EXPECT_GT(plane.springs, 0);
  EXPECT_GT(plane.positions.col(2).minCoeff(), 1.0 - 1e-9);           // on the box, not in it
  EXPECT_LT(top_plane.z(), 0.0);                                      // the press pushes down ...
  EXPECT_LT(std::abs(top_plane.x()), 1e-3 * std::abs(top_plane.z()))  // ... and not sideways
      << "x reaction " << top_plane.x() << ", z " << top_plane.z();
  // Point springs, given ten times the iterations, are still creeping: a sideways reaction is left.
  const FkResult point = solve("point", 10 * plane.iterations, &top_point);
  EXPECT_EQ(point.status, FkStatus::IterationCap) << point.BriefReport();
  EXPECT_GT(std::abs(top_point.x()), 10 * std::abs(top_plane.x()));
  std::printf(
      "[ measured ] sliding contact: plane converged in %d iterations, x/z reaction %.2e; point "
      "after %d: "
      "%.2e, residual ratio %.3g\n",
      plane.iterations, top_plane.x() / top_plane.z(), point.iterations,
      top_point.x() / top_point.z(), point.gradient_ratio);
}

TEST(CollisionResponse, OptionsAreValidated) {
  CollisionOptions o;
  std::string why;
  EXPECT_TRUE(o.IsValid(&why));
  // Names of the enum options are checked where they are read, naming the value and the names.
  EXPECT_THROW(SpringUpdateFromString("magic"), std::invalid_argument);
  try {
    (void)SelfTargetFromString("nearest");
    ADD_FAILURE() << "no exception for 'nearest'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'nearest'; expected one of: auto, walk"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(SelfSpringFromString("glue"), std::invalid_argument);
  EXPECT_THROW(ObstacleSpringFromString("line"), std::invalid_argument);
  EXPECT_EQ(ToString(SelfTargetFromString("walk")), "walk");
  o.stiffness = -1;
  EXPECT_FALSE(o.IsValid(&why));
  o = CollisionOptions();
  o.check_interval = 0;
  EXPECT_FALSE(o.IsValid(&why));
  // Self-collision on a prism mesh is refused with a clear message (through the solver).
  Scene crawler = MakeRobot("dea_crawler", 4);
  crawler.solver.collision.self = true;
  auto model = std::make_shared<const Model>(crawler);
  auto solver = MakeFkSolver(model, crawler.solver);
  const FkResult r = solver->Solve(crawler.rest_actuation());
  EXPECT_EQ(r.status, FkStatus::InvalidInput);
  EXPECT_NE(r.message.find("tet-only"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace softkin
