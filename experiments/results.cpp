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

#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/utsname.h>
#include <unistd.h>

namespace softkin {

namespace fs = std::filesystem;

std::string ResultDir(const std::string& root, const std::string& name) {
  fs::path p = fs::path(root) / name;
  std::error_code ec;
  if (fs::exists(root, ec) && !fs::is_directory(root, ec))
    throw std::invalid_argument("--results '" + root +
                                "' is a file; expected a folder for the "
                                "results (created if missing)");
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
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  ::close(fd);
  Read(true);
  opened_ = records_.size();
}

void ResumeJournal::Read(bool report) {
  records_.clear();
  std::ifstream in(path_);
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
    if (report)
      std::fprintf(stderr,
                   "  %s:%d: not a complete JSON record (an interrupted write?); that unit is "
                   "computed again\n",
                   path_.c_str(), lineno);
  }
}

void ResumeJournal::Reload() { Read(false); }

const nlohmann::json* ResumeJournal::Reuse(const nlohmann::json& key) {
  for (std::size_t i = records_.size(); i-- > 0;)
    if (records_[i]["key"] == key) {
      if (i < opened_) ++reused_;
      return &records_[i]["row"];
    }
  return nullptr;
}

void ResumeJournal::Append(const nlohmann::json& key, const nlohmann::json& row) {
  nlohmann::json record = {{"key", key}, {"row", row}};
  std::string line = record.dump() + "\n";
  // Read and write: the last byte is read to see whether a killed writer cut its line.
  const int fd = ::open(path_.c_str(), O_RDWR | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write " + path_ + ": " + std::strerror(errno));
  // One writer at a time; a lock that the file system does not support (ENOLCK, ENOSYS) leaves
  // O_APPEND's single write per record.
  const bool locked = ::flock(fd, LOCK_EX) == 0;
  struct stat st {};
  char last = '\n';
  if (::fstat(fd, &st) == 0 && st.st_size > 0 && ::pread(fd, &last, 1, st.st_size - 1) != 1)
    last = '\n';
  if (last != '\n') line.insert(line.begin(), '\n');  // a record cut by a killed writer
  std::size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = ::write(fd, line.data() + done, line.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += static_cast<std::size_t>(n);
  }
  const int err = errno;
  if (locked) ::flock(fd, LOCK_UN);
  ::close(fd);
  if (done != line.size())
    throw std::runtime_error("cannot write " + path_ + ": " + std::strerror(err));
  records_.push_back(std::move(record));
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
