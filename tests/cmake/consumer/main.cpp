// Downstream use of an installed SoftKin (softkin::solver): build an embedded robot scene and
// report its size.
#include <softkin/solver/robots/robots.hpp>

#include <cstdio>
#include <exception>

int main() {
  try {
    const softkin::Scene scene = softkin::MakeRobot("three_chamber", 3);
    scene.validate();
    std::printf("three_chamber res 3: %d tets, %d vertices, %d actuators\n", scene.mesh.num_tets(),
                scene.mesh.num_vertices(), scene.num_actuators());
    return scene.mesh.num_tets() > 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "softkin_consumer: %s\n", e.what());
    return 1;
  }
}
