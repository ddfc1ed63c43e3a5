#include "softkin/experiments/cli_tessellate.hpp"

#include "softkin/experiments/cli_args.hpp"
#include "softkin/experiments/results.hpp"
#include "softkin/solver/common/memory_guard.hpp"
#include "softkin/solver/common/text_format.hpp"
#include "softkin/solver/mesh/io/mesh_io.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace softkin {

CLI::App* AddTessellateCommand(CLI::App* app, TessellateCommandArgs* a) {
  auto* tess = app->add_subcommand(
      "tessellate",
      "Volume tessellation T(S_c, S_b) (thesis Sec. 3.2.1): a labelled tet mesh of a closed body "
      "surface with a closed chamber surface inside it, by CGAL Mesh_3 (docs/remeshing.md). "
      "Region 0 = body, 1 = chamber");
  TessellationOptions& o = a->options;
  tess->add_option("--body", a->body, "Outer surface S_b: closed, .obj or .stl, mm")->required();
  tess->add_option("--chamber", a->chamber,
                   "Chamber surface S_c strictly inside S_b: closed, .obj or .stl, mm")
      ->required();
  tess->add_option(
          "--out", a->out,
          "Output mesh by extension: .vtu (ParaView), .vtk (legacy VTK), .msh (Gmsh 2.2) or "
          ".node (TetGen .node + .ele)")
      ->required();
  tess->add_option("--size", o.cell_size,
                   "Largest tet: bound on its circumradius (Mesh_3 cell_size), mm (default 2)");
  tess->add_option("--facet-size", o.facet_size,
                   "Bound on surface facet size, mm (default: --size)");
  tess->add_option(
      "--facet-distance", o.facet_distance,
      "Bound on the distance of a facet to the input surface, mm (default: --size / 10)");
  tess->add_option(
      "--feature-angle", o.feature_angle,
      "Protect input edges sharper than this dihedral angle, degrees (0: none; default 60)");
  tess->add_option("--seed", o.seed, "Seed of Mesh_3's random choices (default 1)");
  tess->add_option("--json", a->json_out,
                   "Write the report (tets per region, volumes, time) as JSON to this file");
  return tess;
}

namespace {

/// Throws "NAME: expected EXPECTED, got GOT" unless ok.
void CheckOption(const char* name, bool ok, const std::string& expected, double got) {
  if (ok) return;
  std::ostringstream os;
  os << name << ": expected " << expected << ", got " << got;
  throw std::invalid_argument(os.str());
}

/// The extension of --out (".vtu", ".vtk", ".msh" or ".node"); anything else throws.
std::string OutputExtension(const std::string& out) {
  const auto dot = out.find_last_of('.');
  const std::string ext = dot == std::string::npos ? "" : out.substr(dot);
  if (ext != ".vtu" && ext != ".vtk" && ext != ".msh" && ext != ".node")
    throw std::invalid_argument(
        "--out: expected a file name ending in .vtu, .vtk, .msh or .node, got '" + out + "'");
  return ext;
}

void WriteTessellation(const std::string& out, const std::string& ext, const Mesh& mesh) {
  if (ext == ".vtu")
    WriteVtu(out, mesh, mesh.vertices);
  else if (ext == ".vtk")
    WriteVtk(out, mesh);
  else if (ext == ".msh")
    WriteGmsh(out, mesh);
  else
    WriteTetGen(out.substr(0, out.size() - ext.size()), mesh);
}

}  // namespace

int RunTessellateCommand(const TessellateCommandArgs& a) {
  const TessellationOptions& o = a.options;
  CheckOption("--size", o.cell_size > 0 && std::isfinite(o.cell_size), "a size > 0 mm",
              o.cell_size);
  CheckOption("--facet-size", o.facet_size >= 0, "a size >= 0 mm (0: --size)", o.facet_size);
  CheckOption("--facet-distance", o.facet_distance >= 0, "a distance >= 0 mm (0: --size / 10)",
              o.facet_distance);
  CheckOption("--feature-angle", o.feature_angle >= 0 && o.feature_angle < 180,
              "an angle in [0, 180) degrees", o.feature_angle);
  const std::string ext = OutputExtension(a.out);
  // A TetGen .node comes with its .ele, written beside it.
  const std::string ele =
      ext == ".node" ? a.out.substr(0, a.out.size() - ext.size()) + ".ele" : std::string();
  CheckCommandPaths({{"--body", a.body}, {"--chamber", a.chamber}},
                    {{"--out", a.out}, {"--out's .ele", ele}, {"--json", a.json_out}});
  const TriangleSurface body = ReadSurfaceMesh(a.body);
  const TriangleSurface chamber = ReadSurfaceMesh(a.chamber);
  const double tets = EstimateTessellationTets(chamber, body, o);
  CheckMemoryEstimate("--size " + FormatNumber(o.cell_size), tets * kTessellationBytesPerTet,
                      "about " + FormatNumber(tets) + " tets for these surfaces",
                      "use a larger --size");
  std::cerr << "softkin tessellate: meshing, about " << FormatNumber(tets)
            << " tets expected (CGAL Mesh_3 reports nothing until it is done)\n";
  TessellationReport rep;
  const Mesh mesh = Tessellate(chamber, body, o, &rep);
  WriteTessellation(a.out, ext, mesh);
  std::cout << "wrote " << a.out << ": " << rep.tets << " tets (body " << rep.body_tets
            << ", chamber " << rep.chamber_tets << "), " << rep.vertices
            << " vertices; volume body " << rep.body_volume << " mm^3 (surfaces enclose "
            << rep.body_enclosed << "), chamber " << rep.chamber_volume << " mm^3 ("
            << rep.chamber_enclosed << "); " << rep.seconds << " s\n";
  if (!a.json_out.empty())
    WriteJson(a.json_out, {{"out", a.out},
                           {"tets", rep.tets},
                           {"body_tets", rep.body_tets},
                           {"chamber_tets", rep.chamber_tets},
                           {"vertices", rep.vertices},
                           {"body_volume", rep.body_volume},
                           {"chamber_volume", rep.chamber_volume},
                           {"body_enclosed", rep.body_enclosed},
                           {"chamber_enclosed", rep.chamber_enclosed},
                           {"seconds", rep.seconds},
                           {"cell_size", o.cell_size},
                           {"seed", o.seed}});
  return 0;
}

}  // namespace softkin
