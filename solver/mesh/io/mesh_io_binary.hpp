#pragma once
/// \file mesh_io_binary.hpp
/// Private helpers for the binary parts of mesh files (not public API): numbers of a named type
/// read from a byte range in either byte order, with errors that name the byte offset, and base64
/// decoding for VTK XML files.
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "softkin/solver/mesh/io/mesh_io_detail.hpp"

namespace softkin {
namespace detail {

/// A fixed-size number type of a binary array.
enum class NumType : std::uint8_t { I8, U8, I16, U16, I32, U32, I64, U64, F32, F64, None };

inline int NumSize(NumType t) {
  switch (t) {
    case NumType::I8:
    case NumType::U8:
      return 1;
    case NumType::I16:
    case NumType::U16:
      return 2;
    case NumType::I32:
    case NumType::U32:
    case NumType::F32:
      return 4;
    case NumType::I64:
    case NumType::U64:
    case NumType::F64:
      return 8;
    case NumType::None:
      break;
  }
  return 0;
}

inline bool NumIsInteger(NumType t) { return t != NumType::F32 && t != NumType::F64; }

/// The type of a VTK XML type name (Int8 ... Float64) or legacy name (unsigned_char, int, long,
/// float, double, vtktypeint64, vtkIdType, ...); None if unknown. Case-insensitive.
inline NumType NumTypeOf(std::string_view name) {
  std::string n(name);
  for (char& c : n) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  static const std::pair<const char*, NumType> kNames[] = {{"int8", NumType::I8},
                                                           {"char", NumType::I8},
                                                           {"vtktypeint8", NumType::I8},
                                                           {"uint8", NumType::U8},
                                                           {"unsigned_char", NumType::U8},
                                                           {"vtktypeuint8", NumType::U8},
                                                           {"int16", NumType::I16},
                                                           {"short", NumType::I16},
                                                           {"vtktypeint16", NumType::I16},
                                                           {"uint16", NumType::U16},
                                                           {"unsigned_short", NumType::U16},
                                                           {"vtktypeuint16", NumType::U16},
                                                           {"int32", NumType::I32},
                                                           {"int", NumType::I32},
                                                           {"vtktypeint32", NumType::I32},
                                                           {"uint32", NumType::U32},
                                                           {"unsigned_int", NumType::U32},
                                                           {"vtktypeuint32", NumType::U32},
                                                           {"int64", NumType::I64},
                                                           {"long", NumType::I64},
                                                           {"vtktypeint64", NumType::I64},
                                                           {"vtkidtype", NumType::I64},
                                                           {"uint64", NumType::U64},
                                                           {"unsigned_long", NumType::U64},
                                                           {"vtktypeuint64", NumType::U64},
                                                           {"float32", NumType::F32},
                                                           {"float", NumType::F32},
                                                           {"vtktypefloat32", NumType::F32},
                                                           {"float64", NumType::F64},
                                                           {"double", NumType::F64},
                                                           {"vtktypefloat64", NumType::F64}};
  for (const auto& [s, t] : kNames)
    if (n == s) return t;
  return NumType::None;
}

inline bool HostIsLittleEndian() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

/// Cursor over bytes [p, end) of a file whose data starts at `begin` (offsets are counted from
/// there). Numbers are read in the file's byte order.
class ByteReader {
 public:
  ByteReader(std::string path, const char* begin, const char* p, const char* end,
             bool little_endian)
      : path_(std::move(path)),
        begin_(begin),
        p_(p),
        end_(end),
        swap_(little_endian != HostIsLittleEndian()) {}

  long long Offset() const { return static_cast<long long>(p_ - begin_); }
  const char* Ptr() const { return p_; }
  std::string Here() const { return AtByte(Offset()); }
  std::string AtByte(long long off) const { return path_ + ": byte offset " + std::to_string(off); }
  void SetSwap(bool swap) { swap_ = swap; }

  [[noreturn]] void FailHere(const std::string& what, const std::string& expected) const {
    Fail(Here(), what, expected);
  }

  /// Reads one number of type t as a double (64-bit integers above 2^53 lose precision).
  double Number(NumType t, const char* what) {
    Need(NumSize(t), what);
    switch (t) {
      case NumType::I8:
        return Raw<std::int8_t>();
      case NumType::U8:
        return Raw<std::uint8_t>();
      case NumType::I16:
        return Raw<std::int16_t>();
      case NumType::U16:
        return Raw<std::uint16_t>();
      case NumType::I32:
        return Raw<std::int32_t>();
      case NumType::U32:
        return Raw<std::uint32_t>();
      case NumType::I64:
        return static_cast<double>(Raw<std::int64_t>());
      case NumType::U64:
        return static_cast<double>(Raw<std::uint64_t>());
      case NumType::F32:
        return Raw<float>();
      case NumType::F64:
        return Raw<double>();
      case NumType::None:
        break;
    }
    FailHere(std::string("no number type for ") + what, "a known number type");
  }

  /// Reads one integer of type t (an integer type) exactly.
  long long Integer(NumType t, const char* what) {
    Need(NumSize(t), what);
    switch (t) {
      case NumType::I64:
        return Raw<std::int64_t>();
      case NumType::U64: {
        const std::uint64_t v = Raw<std::uint64_t>();
        if (v > static_cast<std::uint64_t>(LLONG_MAX))
          Fail(AtByte(Offset() - 8), std::string(what) + " " + std::to_string(v) + " is too large",
               std::string(what) + " below 2^63");
        return static_cast<long long>(v);
      }
      default:
        return static_cast<long long>(Number(t, what));
    }
  }

  void Skip(long long n, const char* what) {
    Need(n, what);
    p_ += n;
  }

 private:
  void Need(long long n, const char* what) const {
    if (n < 0 || end_ - p_ < n)
      FailHere(std::string("data ends inside ") + what,
               std::to_string(n) + " more bytes for " + what + " (the file is truncated?)");
  }
  template <typename T>
  T Raw() {
    unsigned char b[sizeof(T)];
    std::memcpy(b, p_, sizeof(T));
    if (swap_)
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    T v;
    std::memcpy(&v, b, sizeof(T));
    p_ += sizeof(T);
    return v;
  }

  std::string path_;
  const char* begin_;
  const char* p_;
  const char* end_;
  bool swap_;
};

/// Decodes base64 text (whitespace ignored). '=' padding ends a block and decoding goes on with
/// the next one (VTK may encode a header and its data as two blocks). Returns false on a bad
/// character; the decoded bytes are appended to *out.
inline bool DecodeBase64(std::string_view text, std::string* out) {
  unsigned buf = 0;
  int bits = 0;
  for (char c : text) {
    int v;
    if (c >= 'A' && c <= 'Z')
      v = c - 'A';
    else if (c >= 'a' && c <= 'z')
      v = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      v = c - '0' + 52;
    else if (c == '+')
      v = 62;
    else if (c == '/')
      v = 63;
    else if (c == '=') {
      buf = 0;
      bits = 0;
      continue;
    } else if (c == ' ' || c == '\n' || c == '\r' || c == '\t')
      continue;
    else
      return false;
    buf = (buf << 6) | static_cast<unsigned>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out->push_back(static_cast<char>((buf >> bits) & 0xFF));
    }
  }
  return true;
}

}  // namespace detail
}  // namespace softkin
