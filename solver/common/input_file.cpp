/// \file input_file.cpp
/// CheckInputFile (input_file.hpp).
#include "softkin/solver/common/input_file.hpp"

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace softkin {

void CheckInputFile(const std::string& path, const std::string& expected) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status s = fs::status(path, ec);
  if (ec || !fs::exists(s) || fs::is_regular_file(s)) return;
  std::string what = "is not a regular file";
  switch (s.type()) {
    case fs::file_type::directory:
      what = "is a folder";
      break;
    case fs::file_type::fifo:
      what = "is a FIFO (a named pipe)";
      break;
    case fs::file_type::character:
      what = "is a character device";
      break;
    case fs::file_type::block:
      what = "is a block device";
      break;
    case fs::file_type::socket:
      what = "is a socket";
      break;
    default:
      break;
  }
  throw std::invalid_argument(path + ": " + what + "; expected " + expected);
}

}  // namespace softkin
