#pragma once
/// \file input_file.hpp
/// What an input path is, said before a reader opens it: a folder, a device, a FIFO or a socket
/// given where a file is expected used to be reported as "not found", "empty", "truncated" or a
/// bare stream error, and a FIFO without a writer made a reader wait forever.
#include <string>

namespace softkin {

/// Throws std::invalid_argument "<path>: is a folder; expected <expected>" (or "is a FIFO", "is
/// a character device", "is a block device", "is a socket") if `path` exists and is not a
/// regular file. A path that does not exist passes: the reader reports it in its own words.
void CheckInputFile(const std::string& path, const std::string& expected);

}  // namespace softkin
