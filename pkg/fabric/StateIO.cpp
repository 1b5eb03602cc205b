#include "fabric/StateIO.hpp"
#include "core/Errors.hpp"
#include <cstdint>
#include <cstring>
#include <fstream>

namespace woven {

static const char kMagic[8] = {'W', 'O', 'V', 'E', 'N', 'S', 'T', '1'};

void saveState(const std::string& path, const KinematicState& s) {
  std::ofstream o(path, std::ios::binary);
  if (!o) throw std::runtime_error("woven: cannot write state file " + path);
  const std::int64_t n = static_cast<std::int64_t>(s.pos.size()), step = s.step;
  o.write(kMagic, 8);
  o.write(reinterpret_cast<const char*>(&n), 8);
  o.write(reinterpret_cast<const char*>(&step), 8);
  o.write(reinterpret_cast<const char*>(&s.time), 8);
  for (const Vec3& p : s.pos) o.write(reinterpret_cast<const char*>(p.data()), 24);
  for (const Vec3& v : s.vel) o.write(reinterpret_cast<const char*>(v.data()), 24);
  if (!o) throw std::runtime_error("woven: write failed for " + path);
}

KinematicState loadState(const std::string& path, long expectNodes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("woven: cannot read state file " + path);
  char magic[8];
  std::int64_t n = 0, step = 0;
  KinematicState s;
  in.read(magic, 8);
  in.read(reinterpret_cast<char*>(&n), 8);
  in.read(reinterpret_cast<char*>(&step), 8);
  in.read(reinterpret_cast<char*>(&s.time), 8);
  if (!in || std::memcmp(magic, kMagic, 8) != 0 || n < 0)
    throw std::runtime_error("woven: " + path + " is not a woven state file");
  if (expectNodes >= 0 && n != expectNodes)
    throw ParameterError("state", path + " with " + fmt(n) + " nodes", "a state of this fabric (" + fmt(expectNodes) + " nodes)");
  s.step = step;
  s.pos.resize(n);
  s.vel.resize(n);
  for (auto& p : s.pos) in.read(reinterpret_cast<char*>(p.data()), 24);
  for (auto& v : s.vel) in.read(reinterpret_cast<char*>(v.data()), 24);
  if (!in) throw std::runtime_error("woven: " + path + " is truncated");
  return s;
}

}  // namespace woven
