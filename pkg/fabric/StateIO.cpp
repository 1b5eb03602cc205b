#include "fabric/StateIO.hpp"
#include "core/Errors.hpp"
#include <cstdint>
#include <cstring>
#include <fstream>

namespace woven {

static const char kMagic1[8] = {'W', 'O', 'V', 'E', 'N', 'S', 'T', '1'};
static const char kMagic2[8] = {'W', 'O', 'V', 'E', 'N', 'S', 'T', '2'};

void saveState(const std::string& path, const KinematicState& s) {
  std::ofstream o(path, std::ios::binary);
  if (!o) throw std::runtime_error("woven: cannot write state file " + path);
  const std::int64_t n = static_cast<std::int64_t>(s.pos.size()), step = s.step;
  const bool sections = s.flat.size() == s.pos.size() && s.dir.size() == s.pos.size();
  o.write(sections ? kMagic2 : kMagic1, 8);
  o.write(reinterpret_cast<const char*>(&n), 8);
  o.write(reinterpret_cast<const char*>(&step), 8);
  o.write(reinterpret_cast<const char*>(&s.time), 8);
  if (sections) o.write(reinterpret_cast<const char*>(&s.lastDt), 8);
  for (const Vec3& p : s.pos) o.write(reinterpret_cast<const char*>(p.data()), 24);
  for (const Vec3& v : s.vel) o.write(reinterpret_cast<const char*>(v.data()), 24);
  if (sections) {
    o.write(reinterpret_cast<const char*>(s.flat.data()), 8 * n);
    for (const Vec3& d : s.dir) o.write(reinterpret_cast<const char*>(d.data()), 24);
  }
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
  const bool v2 = std::memcmp(magic, kMagic2, 8) == 0;
  if (!in || !(v2 || std::memcmp(magic, kMagic1, 8) == 0) || n < 0)
    throw std::runtime_error("woven: " + path + " is not a woven state file");
  if (expectNodes >= 0 && n != expectNodes)
    throw ParameterError("state", path + " with " + fmt(n) + " nodes", "a state of this fabric (" + fmt(expectNodes) + " nodes)");
  s.step = step;
  if (v2) in.read(reinterpret_cast<char*>(&s.lastDt), 8);
  s.pos.resize(n);
  s.vel.resize(n);
  for (auto& p : s.pos) in.read(reinterpret_cast<char*>(p.data()), 24);
  for (auto& v : s.vel) in.read(reinterpret_cast<char*>(v.data()), 24);
  if (v2) {
    s.flat.resize(n);
    s.dir.resize(n);
    in.read(reinterpret_cast<char*>(s.flat.data()), 8 * n);
    for (auto& d : s.dir) in.read(reinterpret_cast<char*>(d.data()), 24);
  }
  if (!in) throw std::runtime_error("woven: " + path + " is truncated");
  return s;
}

}  // namespace woven
