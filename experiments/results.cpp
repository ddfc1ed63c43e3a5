#include "softkin/experiments/results.hpp"

#include "softkin/solver/common/output_file.hpp"

#include "softkin/solver/collision/collision_response.hpp"

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <sys/utsname.h>

namespace softkin {

namespace fs = std::filesystem;

std::string ResultDir(const std::string& root, const std::string& name) {
  fs::path p = fs::path(root) / name;
  std::error_code ec;
  fs::create_directories(p, ec);
  if (ec)
    throw std::runtime_error("cannot create result folder " + p.string() + ": " + ec.message());
  return p.string();
}

std::string GitCommit() {
  std::string cmd = std::string("git -C '") + SOFTKIN_SOURCE_DIR + "' rev-parse HEAD 2>/dev/null";
  FILE* f = popen(cmd.c_str(), "r");
  if (!f) return "unknown";
  char buf[128] = {0};
  std::string out;
  if (fgets(buf, sizeof(buf), f)) out = buf;
  pclose(f);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  if (out.empty()) return "unknown";
  FILE* g = popen((std::string("git -C '") + SOFTKIN_SOURCE_DIR +
                   "' status --porcelain --untracked-files=no 2>/dev/null")
                      .c_str(),
                  "r");
  if (g) {
    if (fgets(buf, sizeof(buf), g)) out += "-dirty";
    pclose(g);
  }
  return out;
}

nlohmann::json MachineInfo() {
  nlohmann::json j;
  struct utsname u;
  if (uname(&u) == 0) {
    j["host"] = u.nodename;
    j["system"] = std::string(u.sysname) + " " + u.release;
    j["arch"] = u.machine;
  }
  j["hardware_threads"] = std::thread::hardware_concurrency();
  std::ifstream cpu("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpu, line))
    if (line.rfind("model name", 0) == 0) {
      j["cpu"] = line.substr(line.find(':') + 2);
      break;
    }
  std::time_t t = std::time(nullptr);
  char ts[64];
  std::strftime(ts, sizeof(ts), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  j["utc"] = ts;
  return j;
}

void WriteJson(const std::string& path, const nlohmann::json& j) {
  OutputFile f(path);  // atomic: a failed write leaves the old file
  f.stream() << std::setw(2) << j << "\n";
  f.Commit();
}

CsvWriter::CsvWriter(const std::string& path, const std::vector<std::string>& header)
    : path_(path), header_(header), out_(path) {
  if (!out_) throw std::runtime_error("cannot write " + path);
  RowStrings(header);
}

void CsvWriter::Row(const std::vector<double>& values) {
  std::vector<std::string> s;
  s.reserve(values.size());
  for (double v : values) {
    std::ostringstream os;
    os << std::setprecision(10) << v;
    s.push_back(os.str());
  }
  RowStrings(s);
}

void CsvWriter::RowJson(const nlohmann::json& row) {
  std::vector<std::string> s;
  s.reserve(header_.size());
  for (const auto& k : header_) {
    const auto it = row.find(k);
    if (it == row.end() || it->is_null()) {
      s.emplace_back();
    } else if (it->is_string()) {
      s.push_back(it->get<std::string>());
    } else if (it->is_number_integer() || it->is_boolean()) {
      s.push_back(it->dump());
    } else {
      std::ostringstream os;
      os << std::setprecision(10) << it->get<double>();
      s.push_back(os.str());
    }
  }
  RowStrings(s);
}

void CsvWriter::RowStrings(const std::vector<std::string>& values) {
  if (values.size() != header_.size())
    throw std::logic_error(path_ + ": row has " + std::to_string(values.size()) +
                           " values, header has " + std::to_string(header_.size()));
  for (size_t i = 0; i < values.size(); ++i) out_ << (i ? "," : "") << values[i];
  out_ << "\n";
  out_.flush();
}

ResumeJournal::ResumeJournal(const std::string& path) : path_(path) {
  {
    std::ifstream in(path);
    std::string line;
    int lineno = 0;
    while (std::getline(in, line)) {
      ++lineno;
      if (line.empty()) continue;
      try {
        nlohmann::json j = nlohmann::json::parse(line);
        if (j.is_object() && j.contains("key") && j.contains("row")) {
          records_.push_back(std::move(j));
          continue;
        }
      } catch (const nlohmann::json::exception&) {
      }
      std::fprintf(stderr,
                   "  %s:%d: not a complete JSON record (an interrupted write?); that unit is "
                   "computed again\n",
                   path.c_str(), lineno);
    }
  }
  out_.open(path, std::ios::app);
  if (!out_) throw std::runtime_error("cannot write " + path);
}

const nlohmann::json* ResumeJournal::Reuse(const nlohmann::json& key) {
  for (auto it = records_.rbegin(); it != records_.rend(); ++it)
    if ((*it)["key"] == key) {
      ++reused_;
      return &(*it)["row"];
    }
  return nullptr;
}

void ResumeJournal::Append(const nlohmann::json& key, const nlohmann::json& row) {
  out_ << nlohmann::json{{"key", key}, {"row", row}}.dump() << "\n";
  out_.flush();
  if (!out_) throw std::runtime_error("cannot write " + path_);
  records_.push_back({{"key", key}, {"row", row}});
}

nlohmann::json CollisionCheckJson(const CollisionCheck& check) {
  return {{"collision_free", check.collision_free()},
          {"self_contacts", check.self_contacts},
          {"obstacle_contacts", check.obstacle_contacts},
          {"max_penetration_mm", check.max_penetration},
          {"self_penetration_mm", check.self_penetration},
          {"obstacle_penetration_mm", check.obstacle_penetration},
          {"inverted_elements", check.inverted_elements},
          {"inverted_body_elements", check.inverted_body_elements},
          {"tangled_contacts", check.tangled_contacts}};
}

}  // namespace softkin
