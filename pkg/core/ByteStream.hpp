// Plain values to and from a byte string: the state file (fabric/StateIO), the engine snapshot
// (engine/Snapshot) and the collision stage's memory (engine/StageMemory) are written and read with
// these. Values go as their bytes, so only types whose bytes are their value (trivially copyable
// structs, Eigen's fixed-size matrices) of this build; a reader never reads past the end: it calls its owner's fail(what), which names the file or the parameter and throws.
#pragma once

#include <cstdint>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace woven {

struct ByteWriter {
  std::string b;

  template <class T>
  void put(const T& v) {
    b.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void bytes(const void* p, std::size_t n) { b.append(static_cast<const char*>(p), n); }
  /// The elements only (the reader is told the count).
  template <class T>
  void arr(const std::vector<T>& a) {
    bytes(a.data(), a.size() * sizeof(T));
  }
  /// The count, then the elements.
  template <class T>
  void vec(const std::vector<T>& a) { put(static_cast<std::uint64_t>(a.size())), arr(a); }
  /// The count, the record size, then the elements: a reader of another layout can tell, and skip it.
  template <class T>
  void sized(const std::vector<T>& a) {
    put(static_cast<std::uint64_t>(a.size())), put(static_cast<std::uint64_t>(sizeof(T))), arr(a);
  }
};

class ByteReader {
 public:
  using Fail = std::function<void(const std::string&)>;
  /// Reads `b` from offset `at`; `fail(what)` throws the owner's error and must not return.
  ByteReader(const std::string& b, std::size_t at, Fail fail) : b_(b), at_(at), fail_(std::move(fail)) {}

  [[noreturn]] void fail(const std::string& what) const {
    fail_(what);
    throw std::logic_error("woven: ByteReader's fail returned: " + what);
  }
  std::size_t at() const { return at_; }
  std::size_t left() const { return b_.size() - at_; }
  void need(std::size_t n) const {
    if (n > left()) fail("truncated");
  }
  void skip(std::size_t n) { need(n), at_ += n; }

  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(static_cast<void*>(&v), b_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  /// n elements (ByteWriter::arr).
  template <class T>
  void arr(std::vector<T>& a, std::size_t n) {
    if (n > left() / sizeof(T)) fail("truncated");
    a.resize(n);
    if (n) std::memcpy(static_cast<void*>(a.data()), b_.data() + at_, n * sizeof(T));
    at_ += n * sizeof(T);
  }
  /// A count that leaves at least `least` bytes per item in what is left.
  std::uint64_t count(std::size_t least) {
    const auto n = get<std::uint64_t>();
    if (n > left() / (least ? least : 1)) fail("a count past the end");
    return n;
  }
  /// ByteWriter::vec.
  template <class T>
  void vec(std::vector<T>& a) { arr(a, get<std::uint64_t>()); }
  /// ByteWriter::sized: false (and `a` empty, the block skipped) where the record size is not this
  /// build's.
  template <class T>
  bool sized(std::vector<T>& a) {
    const auto n = get<std::uint64_t>(), size = get<std::uint64_t>();
    if (size == 0 || n > left() / size) fail("a block past the end");
    if (size != sizeof(T)) {
      at_ += n * size, a.clear();
      return false;
    }
    arr(a, n);
    return true;
  }

 private:
  const std::string& b_;
  std::size_t at_;
  Fail fail_;
};

}  // namespace woven
