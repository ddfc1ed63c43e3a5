// Downstream use of SoftKin's FK core alone (softkin::core: no CGAL, Ceres or Ipopt): a voxel bar
// whose upper half is a pneumatic chamber, fixed at x = 0, bent by the local-global solver.
#include <softkin/solver/fk/local_global.hpp>
#include <softkin/solver/mesh/mesh_gen.hpp>
#include <softkin/solver/scene/scene.hpp>

#include <cstdio>
#include <exception>
#include <memory>

int main() {
  try {
    softkin::Scene s;
    s.name = "core_bar";
    s.mesh = softkin::VoxelTetMesh(Eigen::Vector3d::Zero(), 2.0, Eigen::Vector3i(10, 2, 2),
                                   [](const Eigen::Vector3d&, const Eigen::Vector3i& cell) {
                                     return cell.z() == 1 ? 1 : 0;  // region 1: the chamber
                                   });
    s.body[0] = softkin::Material{};
    softkin::Actuator a;
    a.name = "chamber";
    a.type = softkin::ActuatorType::Pneumatic;
    a.regions = {1};
    a.min = 1.0;
    a.max = 2.0;
    s.actuators.push_back(a);
    s.fixed =
        softkin::VerticesOnPlane(s.mesh, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), 1e-9);
    s.validate();
    auto model = std::make_shared<const softkin::Model>(s);
    softkin::LocalGlobalSolver solver(model, s.solver);
    const softkin::FkResult r = solver.Solve(Eigen::VectorXd::Constant(1, 1.5));
    const double tip_z = r.positions.col(2).minCoeff();
    std::printf("core bar: %s, lowest z %.3f mm\n", r.BriefReport().c_str(), tip_z);
    // The expanding upper half bends the bar down (towards -z).
    return r.status == softkin::FkStatus::Converged && tip_z < -0.5 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "softkin_core_consumer: %s\n", e.what());
    return 1;
  }
}
