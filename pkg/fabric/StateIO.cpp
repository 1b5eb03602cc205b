#include "fabric/StateIO.hpp"
#include "core/ByteStream.hpp"
#include "core/Errors.hpp"
#include "fabric/Fabric.hpp"
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace woven {

namespace {

const char kMagic3[8] = {'W', 'O', 'V', 'E', 'N', 'S', 'T', '3'};
// 4: the friction book after the other 11 (3 has none); 5: the collision stage's memory after the
// breaks (a length and its bytes).
constexpr std::uint32_t kVersion = 5;
constexpr std::uint64_t kFnvOffset = 1469598103934665603ull, kFnvPrime = 1099511628211ull;

std::uint64_t fnv(const void* data, std::size_t n, std::uint64_t h = kFnvOffset) {
  const unsigned char* p = static_cast<const unsigned char*>(data);
  for (std::size_t k = 0; k < n; ++k) h = (h ^ p[k]) * kFnvPrime;
  return h;
}

void checkPath(const std::string& path) {
  // std::string keeps an embedded NUL, the C library stops at it: "a\0b" would silently write "a".
  if (path.find('\0') != std::string::npos)
    throw ParameterError("path", "'" + path.substr(0, path.find('\0')) + "\\0...'", "a file path without NUL characters");
  if (path.empty()) throw ParameterError("path", "''", "a non-empty file path");
}

std::string errnoText(int err) { return std::strerror(err); }

}  // namespace

std::uint64_t topologyFingerprint(const Fabric& f) {
  std::uint64_t h = kFnvOffset;
  const std::int64_t counts[3] = {f.nNodes(), f.nElems(), f.nYarns()};
  h = fnv(counts, sizeof(counts), h);
  for (const Yarn& y : f.yarns) {
    const std::int64_t ints[6] = {y.firstNode, y.nNodes, y.firstElem, y.nElems, y.material, static_cast<std::int64_t>(y.family)};
    h = fnv(ints, sizeof(ints), h);
    const Real sec[2] = {y.section.width, y.section.thickness};
    h = fnv(sec, sizeof(sec), h);
    // Not E, damping, failure strain or tension-only: a state of the same geometry and masses loads
    // into a weave of another stiffness or damping (a pretensioned weave, then struck undamped).
  }
  h = fnv(f.restLength.data(), f.restLength.size() * sizeof(Real), h);
  h = fnv(f.mass.data(), f.mass.size() * sizeof(Real), h);
  h = fnv(f.secRadius.data(), f.secRadius.size() * sizeof(Real), h);
  return h;
}

void writeFileAtomic(const std::string& path, const std::string& bytes) {
  checkPath(path);
  struct stat st;
  const bool special = ::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode);
  if (special && S_ISDIR(st.st_mode)) throw ParameterError("path", "'" + path + "'", "a file path, not a folder");
  std::string tmp;
  int fd;
  if (special) {
    // A device or a pipe cannot be replaced by a rename (and must not be): write into it, checked.
    fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  } else {
    // The temporary lives in the target's folder so that rename() is atomic (same file system).
    tmp = path + ".tmp.XXXXXX";
    std::vector<char> name(tmp.begin(), tmp.end());
    name.push_back('\0');
    fd = ::mkostemp(name.data(), O_CLOEXEC);
    tmp.assign(name.data());
  }
  if (fd < 0) throw std::runtime_error("woven: cannot write " + path + ": " + errnoText(errno));
  auto failWith = [&](int err, const char* what) {
    ::close(fd);
    if (!tmp.empty()) ::unlink(tmp.c_str());
    throw std::runtime_error(std::string("woven: ") + what + " " + path + " failed: " + errnoText(err) +
                             " (the previous file, if any, is unchanged)");
  };
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t k = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (k < 0) {
      if (errno == EINTR) continue;
      failWith(errno, "writing");
    }
    done += static_cast<std::size_t>(k);
  }
  if (!special || S_ISREG(st.st_mode)) {
    if (::fsync(fd) != 0) failWith(errno, "flushing (fsync)");
  } else if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
    failWith(errno, "flushing (fsync)");
  }
  if (!tmp.empty()) {
    // mkostemp makes the file 0600; give it the permissions an ordinary new file would get.
    const mode_t mask = ::umask(0);
    ::umask(mask);
    ::fchmod(fd, 0666 & ~mask);
  }
  if (::close(fd) != 0) {
    const int err = errno;
    if (!tmp.empty()) ::unlink(tmp.c_str());
    throw std::runtime_error("woven: closing " + path + " failed: " + errnoText(err) + " (the previous file, if any, is unchanged)");
  }
  if (!tmp.empty() && ::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error("woven: renaming the temporary onto " + path + " failed: " + errnoText(err));
  }
  if (!tmp.empty()) {
    // The rename itself is durable once the folder is synced (best effort: some file systems refuse).
    const std::size_t slash = path.rfind('/');
    const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
    const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) ::fsync(dfd), ::close(dfd);
  }
}

void saveState(const std::string& path, const KinematicState& s) {
  checkPath(path);
  const std::int64_t n = static_cast<std::int64_t>(s.pos.size()), ne = static_cast<std::int64_t>(s.alive.size());
  const std::int64_t ny = s.yarns;
  if (s.vel.size() != s.pos.size() || s.flat.size() != s.pos.size() || s.dir.size() != s.pos.size() ||
      s.stiffness.size() != s.alive.size() || s.damping.size() != s.alive.size())
    throw std::logic_error("woven: saveState given an inconsistent state");
  ByteWriter w;
  w.bytes(kMagic3, 8);
  w.put(kVersion);
  w.put(std::uint32_t(0));
  w.put(s.topology);
  w.put(n), w.put(ne), w.put(ny);
  w.put(static_cast<std::int64_t>(s.step));
  w.put(s.time), w.put(s.lastDt);
  w.arr(s.pos), w.arr(s.vel), w.arr(s.flat), w.arr(s.dir);
  w.arr(s.alive), w.arr(s.stiffness), w.arr(s.damping);
  w.put(std::uint8_t(s.booksStarted)), w.put(std::uint8_t(s.springSeen));
  const EnergyBooks& b = s.books;
  for (Real v : {b.kinetic, b.elastic, b.damped, b.work, b.bodyWork, b.contact, b.contactInput, b.spring, b.released, b.initial, b.projection})
    w.put(v);
  w.put(b.friction);
  const BreakageParams& p = s.breakage.params;
  w.put(std::uint8_t(p.enabled)), w.put(p.threshold), w.put(p.filterLength), w.put(p.weibullModulus), w.put(p.seed);
  w.put(static_cast<std::int64_t>(s.breakage.strength.size())), w.arr(s.breakage.strength);
  w.put(static_cast<std::int64_t>(s.breakage.filtered.size())), w.arr(s.breakage.filtered);
  w.put(static_cast<std::int64_t>(s.breakage.log.size()));
  for (const BreakEvent& ev : s.breakage.log) {
    w.put(static_cast<std::int64_t>(ev.step)), w.put(ev.time), w.put(std::int32_t(ev.yarn)), w.put(std::int32_t(ev.element));
    w.put(ev.position);
    w.put(ev.strain), w.put(ev.rawStrain), w.put(ev.energy);
  }
  w.put(static_cast<std::int64_t>(s.contacts.size()));
  w.bytes(s.contacts.data(), s.contacts.size());
  w.put(fnv(w.b.data(), w.b.size()));
  writeFileAtomic(path, w.b);
}

KinematicState loadState(const std::string& path, long expectNodes) {
  checkPath(path);
  std::string buf;
  {
    std::FILE* in = std::fopen(path.c_str(), "rb");
    if (!in) throw ParameterError("path", "'" + path + "'", std::string("a readable woven state file (") + errnoText(errno) + ")");
    char chunk[1 << 16];
    std::size_t k;
    while ((k = std::fread(chunk, 1, sizeof(chunk), in)) > 0) {
      buf.append(chunk, k);
      if (buf.size() > (std::size_t(1) << 36)) break;  // 64 GiB: no state of an addressable fabric is larger
    }
    const bool err = std::ferror(in);
    std::fclose(in);
    if (err) throw ParameterError("path", "'" + path + "'", "a readable woven state file (read error)");
  }
  ByteReader r(buf, 0, [&path](const std::string& what) {
    throw ParameterError("state", "'" + path + "'", "a woven state file (format 3): " + what);
  });
  KinematicState s;
  if (buf.size() < 8) r.fail("the file is truncated");
  if (std::memcmp(buf.data(), "WOVENST", 7) != 0) r.fail("not a woven state file (no WOVENST magic)");
  if (buf[7] != '3') r.fail(std::string("format WOVENST") + buf[7] + " is not supported (re-save it with this woven)");
  r.get<std::uint64_t>();  // the magic
  const std::uint32_t version = r.get<std::uint32_t>();
  if (version < 3 || version > kVersion)
    r.fail("version " + fmt(version) + ", this woven reads versions 3 to " + fmt(kVersion));
  r.get<std::uint32_t>();
  // The checksum first: every later check may then trust the sizes it reads.
  if (buf.size() < 16) r.fail("the file is truncated");
  std::uint64_t stored;
  std::memcpy(&stored, buf.data() + buf.size() - 8, 8);
  if (fnv(buf.data(), buf.size() - 8) != stored) r.fail("checksum mismatch (the file is corrupted, truncated or has trailing bytes)");
  s.topology = r.get<std::uint64_t>();
  const std::int64_t n = r.get<std::int64_t>(), ne = r.get<std::int64_t>(), ny = r.get<std::int64_t>();
  if (n < 0 || ne < 0 || ny < 0 || n > 2147483647 || ne > 2147483647 || ny > 2147483647)
    r.fail("node, element and yarn counts in [0, 2^31)");
  s.yarns = static_cast<long>(ny);
  if (expectNodes >= 0 && n != expectNodes)
    throw ParameterError("state", path + " with " + fmt(n) + " nodes", "a state of this fabric (" + fmt(expectNodes) + " nodes)");
  const std::int64_t step = r.get<std::int64_t>();
  s.time = r.get<Real>(), s.lastDt = r.get<Real>();
  if (step < 0) throw ParameterError("state", "step " + fmt(step), "a step count in [0, 2^63)");
  if (!(std::isfinite(s.time) && s.time >= 0)) throw ParameterError("state", "time " + fmt(s.time), "a time in [0, inf) s");
  if (!(std::isfinite(s.lastDt) && s.lastDt >= 0))
    throw ParameterError("state", "last_dt " + fmt(s.lastDt), "a last time step in [0, dt_crit] s");
  s.step = static_cast<long>(step);
  std::vector<Real> raw;
  const auto vecs = [&](Vec3Array& a) {
    r.arr(raw, static_cast<std::size_t>(3 * n));
    a.resize(n);
    for (std::int64_t i = 0; i < n; ++i) a[i] = Vec3(raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]);
  };
  vecs(s.pos), vecs(s.vel);
  r.arr(s.flat, n);
  vecs(s.dir);
  r.arr(s.alive, ne), r.arr(s.stiffness, ne), r.arr(s.damping, ne);
  s.booksStarted = r.get<std::uint8_t>() != 0, s.springSeen = r.get<std::uint8_t>() != 0;
  EnergyBooks& b = s.books;
  for (Real* v : {&b.kinetic, &b.elastic, &b.damped, &b.work, &b.bodyWork, &b.contact, &b.contactInput, &b.spring, &b.released, &b.initial, &b.projection})
    *v = r.get<Real>();
  b.friction = version >= 4 ? r.get<Real>() : 0.0;
  BreakageParams& p = s.breakage.params;
  p.enabled = r.get<std::uint8_t>() != 0;
  p.threshold = r.get<Real>(), p.filterLength = r.get<Real>(), p.weibullModulus = r.get<Real>();
  p.seed = r.get<std::uint64_t>();
  const std::int64_t nStrength = r.get<std::int64_t>();
  if (nStrength != 0 && nStrength != ny) r.fail("strength count 0 or the yarn count");
  r.arr(s.breakage.strength, nStrength);
  const std::int64_t nFiltered = r.get<std::int64_t>();
  if (nFiltered != 0 && nFiltered != ne) r.fail("filtered-strain count 0 or the element count");
  r.arr(s.breakage.filtered, nFiltered);
  const std::int64_t nLog = r.get<std::int64_t>();
  if (nLog < 0 || nLog > ne) r.fail("break count in [0, elements]");
  s.breakage.log.resize(nLog);
  for (BreakEvent& ev : s.breakage.log) {
    ev.step = r.get<std::int64_t>(), ev.time = r.get<Real>(), ev.yarn = r.get<std::int32_t>(), ev.element = r.get<std::int32_t>();
    for (int k = 0; k < 3; ++k) ev.position[k] = r.get<Real>();
    ev.strain = r.get<Real>(), ev.rawStrain = r.get<Real>(), ev.energy = r.get<Real>();
  }
  if (version >= 5) {
    const std::int64_t nc = r.get<std::int64_t>();
    if (nc < 0 || static_cast<std::uint64_t>(nc) > buf.size() - r.at()) r.fail("contact memory past the end");
    s.contacts.assign(buf.data() + r.at(), static_cast<std::size_t>(nc));
    r.skip(static_cast<std::size_t>(nc));
  }
  r.get<std::uint64_t>();  // the checksum, verified above
  if (r.at() != buf.size()) r.fail(fmt(buf.size() - r.at()) + " trailing bytes after the checksum");

  // Values: each one in its physical range (a checksum only proves the bytes are the ones written).
  const auto bad = [&](const std::string& what, const std::string& allowed) { throw ParameterError("state", what, allowed); };
  for (std::int64_t i = 0; i < n; ++i) {
    if (!s.pos[i].allFinite()) bad("position of node " + fmt(i) + " " + fmt(s.pos[i].norm()), "finite positions [m]");
    if (!s.vel[i].allFinite()) bad("velocity of node " + fmt(i) + " " + fmt(s.vel[i].norm()), "finite velocities [m/s]");
    if (!(s.flat[i] >= 0 && s.flat[i] < 1)) bad("section flattening of node " + fmt(i) + " = " + fmt(s.flat[i]), "eps in [0, 1)");
    if (!(s.dir[i].allFinite() && std::abs(s.dir[i].norm() - 1) <= 1e-6))
      bad("section direction of node " + fmt(i) + " of length " + fmt(s.dir[i].norm()), "unit vectors");
  }
  for (std::int64_t e = 0; e < ne; ++e) {
    if (s.alive[e] > 1) bad("alive flag of element " + fmt(e) + " = " + fmt(int(s.alive[e])), "0 or 1");
    const bool okK = std::isfinite(s.stiffness[e]) && std::isfinite(s.damping[e]) && s.damping[e] >= 0 &&
                     (s.alive[e] ? s.stiffness[e] > 0 : s.stiffness[e] == 0 && s.damping[e] == 0);
    if (!okK) bad("stiffness/damping of element " + fmt(e), "finite values, > 0 stiffness for a live element, 0 for a broken one");
  }
  for (Real v : {b.kinetic, b.elastic, b.damped, b.work, b.bodyWork, b.contact, b.friction, b.contactInput, b.spring, b.released, b.initial, b.projection})
    if (!std::isfinite(v)) bad("energy book " + fmt(v), "finite energies [J]");
  if (b.kinetic < 0 || b.elastic < 0 || b.damped < 0 || b.contactInput < 0 || b.released < 0 || b.spring < 0)
    bad("a negative energy book", "kinetic, elastic, damped, contact input, spring and released energies >= 0 J");
  return s;
}

}  // namespace woven
