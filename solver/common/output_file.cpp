/// \file output_file.cpp
/// OutputFile, CheckOutputPath and CheckDistinctPaths (output_file.hpp).
#include "softkin/solver/common/output_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace softkin {

namespace fs = std::filesystem;

namespace {

/// True if `p` exists and is neither a regular file nor a folder (a device, a FIFO, a socket).
bool IsSpecial(const fs::path& p) {
  std::error_code ec;
  const fs::file_status s = fs::status(p, ec);
  return !ec && fs::exists(s) && !fs::is_regular_file(s) && !fs::is_directory(s);
}

std::string SystemReason() { return errno != 0 ? std::strerror(errno) : "unknown error"; }

/// The folder a path is written into ("." for a bare name).
fs::path Parent(const fs::path& p) {
  const fs::path parent = p.parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

}  // namespace

OutputFile::OutputFile(std::string path, std::ios::openmode mode) : path_(std::move(path)) {
  if (path_.empty()) throw std::runtime_error("output file: empty path; expected a file name");
  const fs::path p(path_);
  if (!IsSpecial(p)) {
    std::error_code ec;
    if (fs::is_directory(p, ec))
      throw std::runtime_error(path_ + ": is a folder; expected a file name");
    tmp_ = (Parent(p) / (p.filename().string() + ".tmp-" + std::to_string(::getpid()))).string();
  }
  errno = 0;
  out_.open(tmp_.empty() ? path_ : tmp_, mode | std::ios::out | std::ios::trunc);
  if (!out_)
    throw std::runtime_error(path_ + ": cannot write (" + SystemReason() +
                             "); expected a writable path in an existing folder");
}

OutputFile::~OutputFile() {
  if (committed_) return;
  out_.close();
  if (!tmp_.empty()) std::remove(tmp_.c_str());
}

void OutputFile::Commit() {
  errno = 0;
  out_.flush();
  const bool flushed = static_cast<bool>(out_);
  out_.close();
  if (!flushed || out_.fail()) {
    const std::string reason = SystemReason();
    if (!tmp_.empty()) std::remove(tmp_.c_str());
    committed_ = true;
    throw std::runtime_error(path_ + ": write error (" + reason +
                             "); expected enough disk space and a writable file" +
                             (tmp_.empty() ? "" : " (the previous file, if any, is unchanged)"));
  }
  committed_ = true;
  if (tmp_.empty()) return;
  std::error_code ec;
  fs::rename(tmp_, path_, ec);
  if (ec) {
    std::remove(tmp_.c_str());
    throw std::runtime_error(path_ + ": cannot replace the file (" + ec.message() +
                             "); expected a writable path");
  }
}

void WriteTextFile(const std::string& path, const std::string& text) {
  OutputFile f(path);
  f.stream() << text;
  f.Commit();
}

void CheckOutputPath(const NamedPath& out) {
  auto fail = [&](const std::string& why, const std::string& expected) {
    throw std::invalid_argument(out.what + " '" + out.path + "': " + why + "; expected " +
                                expected);
  };
  if (out.path.empty()) fail("empty path", "a file name");
  const fs::path p(out.path);
  std::error_code ec;
  if (IsSpecial(p)) return;
  if (fs::is_directory(p, ec)) fail("is a folder", "a file name");
  const fs::path parent = Parent(p);
  if (!fs::exists(parent, ec))
    fail("the folder '" + parent.string() + "' does not exist",
         "a path in an existing folder (create it first)");
  if (!fs::is_directory(parent, ec))
    fail("'" + parent.string() + "' is not a folder", "a path in an existing folder");
  // The file is written beside itself and renamed: the folder must be writable.
  if (::access(parent.c_str(), W_OK | X_OK) != 0)
    fail("no permission to write in '" + parent.string() + "'", "a writable folder");
  if (fs::exists(p, ec) && ::access(p.c_str(), W_OK) != 0)
    fail("no permission to replace the file", "a writable file");
}

void CheckDistinctPaths(const std::vector<NamedPath>& inputs,
                        const std::vector<NamedPath>& outputs) {
  auto key = [](const std::string& path) {
    std::error_code ec;
    const fs::path abs = fs::absolute(fs::path(path)).lexically_normal();
    const fs::path c = fs::weakly_canonical(abs, ec);  // resolves links of the existing part
    return ec ? abs.string() : c.string();
  };
  for (size_t i = 0; i < outputs.size(); ++i) {
    const NamedPath& o = outputs[i];
    if (o.path.empty() || IsSpecial(fs::path(o.path))) continue;
    const std::string k = key(o.path);
    for (const NamedPath& in : inputs)
      if (!in.path.empty() && key(in.path) == k)
        throw std::invalid_argument(o.what + " '" + o.path + "' is the same file as the input " +
                                    in.what + " '" + in.path +
                                    "'; expected an output path that is not an input (writing it "
                                    "would destroy the input)");
    for (size_t j = 0; j < i; ++j)
      if (!outputs[j].path.empty() && key(outputs[j].path) == k)
        throw std::invalid_argument(o.what + " '" + o.path + "' is the same file as the output " +
                                    outputs[j].what + " '" + outputs[j].path +
                                    "'; expected a different path for each output");
  }
}

}  // namespace softkin
