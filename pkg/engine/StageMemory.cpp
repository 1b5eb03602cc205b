// What the collision stage carries from one step to the next, as bytes (CollisionStage::memory):
// the persistent crossings, each CP pair's measure memory (model Gap) or carried contact (model Paper),
// the body contacts of the last step (the measure memory of the next), the velocities the fabric left
// each body with (the host's kick of the next step is measured from them: RigidBody::hostKick), the
// section springs' rest shape and the statistics. State files and snapshots keep it, so that saving a run is a pure
// observation and a run continued from a save is the saving run, bit for bit (before, both sides
// forgot the memory at a save: the saving run then differed from the straight one).
// The crossings and the pair memory go field by field; the carried contacts, body contacts and
// statistics as their bytes with their size, which another build's layout fails (the memory is then
// dropped: the state loads, and the run continues as one that forgot it).
#include "core/ByteStream.hpp"
#include "core/Errors.hpp"
#include "engine/CollisionStage.hpp"
#include <cstring>

namespace woven {

namespace {

// WSM2 adds the bodies' velocities after the body contacts; WSM1 (without them) is read too, and its
// bodies keep the velocities they have.
constexpr char kMemoryMagic[4] = {'W', 'S', 'M', '2'};
constexpr char kMemoryMagic1[4] = {'W', 'S', 'M', '1'};

[[noreturn]] void memoryFails(const std::string& what) {
  throw ParameterError("state", "contact memory: " + what, "the memory a woven collision stage wrote");
}

}  // namespace

// The parsed memory, checked against the fabric before anything is applied.
struct CollisionStage::Memory {
  std::vector<Crossing> crossings;
  std::vector<CPPair> keys;  // the pairs of memo / cache, sorted
  std::vector<PairMemo> memo;
  std::vector<PairCache> cache;
  long cacheClock = 0;
  std::vector<long> sectionStamp;
  std::size_t heldFor = 0;
  std::vector<BodyContact> held;
  Vec3Array bodyVel, bodyAngVel;  // per body at the save (empty: a WSM1 memory)
  std::vector<Real> restFlat;
  Vec3Array restDir;
  std::vector<CollisionStats> stats;
  bool layout = true;
};

std::string CollisionStage::memory() const {
  ByteWriter o;
  o.b.append(kMemoryMagic, 4);
  const std::vector<Crossing>& xs = crossings_.crossings();
  o.put(static_cast<std::uint64_t>(xs.size()));
  for (const Crossing& x : xs) {
    o.put(x.a.cp), o.put(x.a.s), o.put(x.b.cp), o.put(x.b.s), o.put(x.normal);
    o.put(x.measure), o.put(x.lambda), o.put(x.fsA), o.put(x.fsB), o.put(x.apart);
  }
  // The pairs with a memory: the gap model's remembered ones, the paper model's valid carried ones.
  std::vector<std::size_t> kept;
  for (std::size_t k = 0; k < cachePairs_.size(); ++k)
    if ((k < memo_.size() && memo_[k].memo) || (k < cache_.size() && cache_[k].valid)) kept.push_back(k);
  o.put(static_cast<std::uint64_t>(kept.size()));
  for (std::size_t k : kept) {
    o.put(cachePairs_[k].a), o.put(cachePairs_[k].b);
    const PairMemo m = k < memo_.size() ? memo_[k] : PairMemo();
    o.put(std::uint8_t(m.memo)), o.put(std::uint8_t(m.side)), o.put(std::uint8_t(m.held)), o.put(std::int32_t(m.memoPoints));
    for (int q = 0; q < 2; ++q) o.put(m.memoS[q]), o.put(m.memoT[q]), o.put(m.memoMeasure[q]), o.put(m.memoNormal[q]);
  }
  std::vector<PairCache> cache;
  if (!cache_.empty())
    for (std::size_t k : kept) cache.push_back(cache_[k]);
  o.sized(cache);
  o.put(static_cast<std::int64_t>(cacheClock_));
  o.sized(sectionStamp_);
  o.put(static_cast<std::uint64_t>(bodies.size()));
  // The next step's measure memory: none when new settings have just invalidated it (setParams), as
  // the running engine's next step will find none; a restored engine must not find these.
  o.sized(forgetHeld_ ? std::vector<BodyContact>() : bodyContacts_);
  // Without them a continued run's first host kick would be the body's whole velocity change since
  // the bodies were coupled, and the books (body work, contact, work) would part from the straight run.
  for (const RigidBody& b : bodies) o.put(b.vel), o.put(b.angVel);
  o.sized(restFlat_);
  o.sized(restDir_);
  // The statistics continue in a restored engine, its phase clocks from zero: wall-clock times are
  // no state, and would make two saves of one run differ in their bytes.
  CollisionStats counted = stats;
  std::fill(std::begin(counted.seconds), std::end(counted.seconds), Real(0));
  o.sized(std::vector<CollisionStats>{counted});
  return o.b;
}

CollisionStage::Memory CollisionStage::parseMemory(const Fabric& f, const std::string& bytes) const {
  const bool v2 = bytes.size() >= 4 && std::memcmp(bytes.data(), kMemoryMagic, 4) == 0;
  if (!v2 && (bytes.size() < 4 || std::memcmp(bytes.data(), kMemoryMagic1, 4) != 0)) memoryFails("no WSM2 or WSM1 header");
  ByteReader in(bytes, 4, memoryFails);
  Memory m;
  const Index ne = f.nElems();
  const auto n = in.count(8 * sizeof(Real));
  m.crossings.resize(n);
  for (Crossing& x : m.crossings) {
    x.a.cp = in.get<Index>(), x.a.s = in.get<Real>(), x.b.cp = in.get<Index>(), x.b.s = in.get<Real>();
    x.normal = in.get<Vec3>(), x.measure = in.get<Real>(), x.lambda = in.get<Real>();
    x.fsA = in.get<Real>(), x.fsB = in.get<Real>(), x.apart = in.get<Real>();
  }
  const auto nk = in.count(2 * sizeof(Index));
  m.keys.resize(nk), m.memo.resize(nk);
  for (std::size_t k = 0; k < nk; ++k) {
    CPPair& p = m.keys[k];
    p.a = in.get<Index>(), p.b = in.get<Index>();
    if (p.a < 0 || p.b >= ne || !(p.a < p.b) || (k > 0 && !(m.keys[k - 1] < p))) in.fail("pairs out of range or order");
    PairMemo& q = m.memo[k];
    q.memo = in.get<std::uint8_t>() != 0, q.side = in.get<std::uint8_t>() != 0, q.held = in.get<std::uint8_t>() != 0;
    q.memoPoints = in.get<std::int32_t>();
    if (q.memoPoints < 0 || q.memoPoints > 2) in.fail("a pair with more than two remembered points");
    for (int j = 0; j < 2; ++j) {
      q.memoS[j] = in.get<Real>(), q.memoT[j] = in.get<Real>(), q.memoMeasure[j] = in.get<Real>();
      q.memoNormal[j] = in.get<Vec3>();
      if (!(std::isfinite(q.memoS[j]) && std::isfinite(q.memoT[j]) && std::isfinite(q.memoMeasure[j]) &&
            q.memoNormal[j].allFinite()))
        in.fail("a pair's memory not finite");
    }
  }
  m.layout = in.sized(m.cache);
  if (!m.cache.empty() && m.cache.size() != nk) in.fail("carried contacts not one per pair");
  m.cacheClock = static_cast<long>(in.get<std::int64_t>());
  m.layout &= in.sized(m.sectionStamp);
  m.heldFor = in.get<std::uint64_t>();
  m.layout &= in.sized(m.held);
  if (v2) {
    if (m.heldFor > in.left() / (6 * sizeof(Real))) in.fail("body velocities past the end");
    m.bodyVel.resize(m.heldFor), m.bodyAngVel.resize(m.heldFor);
    for (std::size_t k = 0; k < m.heldFor; ++k) {
      m.bodyVel[k] = in.get<Vec3>(), m.bodyAngVel[k] = in.get<Vec3>();
      if (!(m.bodyVel[k].allFinite() && m.bodyAngVel[k].allFinite())) in.fail("a body velocity not finite");
    }
  }
  m.layout &= in.sized(m.restFlat);
  m.layout &= in.sized(m.restDir);
  m.layout &= in.sized(m.stats);
  if (in.left() != 0) in.fail("trailing bytes");
  for (const BodyContact& c : m.held)
    if (c.cp < 0 || c.cp >= ne || c.body < 0 || static_cast<std::size_t>(c.body) >= m.heldFor) in.fail("a body contact out of range");
  for (const PairCache& c : m.cache)
    if (c.contact.cpA < 0 || c.contact.cpB >= ne) in.fail("a carried contact out of range");
  if (!m.sectionStamp.empty() && static_cast<Index>(m.sectionStamp.size()) != ne) in.fail("section stamps not one per CP");
  if (m.restFlat.size() != m.restDir.size() || (!m.restFlat.empty() && m.restFlat.size() != f.secFlat.size()))
    in.fail("rest sections not one per node");
  return m;
}

void CollisionStage::checkMemory(const Fabric& f, const std::string& bytes) const {
  const Memory m = parseMemory(f, bytes);
  CrossingContacts probe;
  probe.set(f, m.crossings, params_);  // throws on a crossing out of range
}

bool CollisionStage::setMemory(const Fabric& f, const std::string& bytes) {
  Memory m = parseMemory(f, bytes);
  if (!m.layout) return false;
  CrossingContacts xs;
  xs.set(f, m.crossings, params_);
  // Committed: the next step's full broad phase lists the pairs afresh, and the memory follows them
  // from these keys (remapCache).
  invalidateCache();
  crossings_ = std::move(xs);
  cachePairs_ = std::move(m.keys);
  const bool gap = params_.model == ContactModel::Gap;
  memo_ = gap ? std::move(m.memo) : std::vector<PairMemo>();
  cache_ = std::move(m.cache);
  cacheClock_ = m.cacheClock;
  sectionStamp_ = std::move(m.sectionStamp);
  bodyContacts_ = std::move(m.held), heldFor_ = m.heldFor, forgetHeld_ = false;
  // The same bodies as the saving run's (a state saved before a body was coupled leaves it as it is).
  if (m.bodyVel.size() == bodies.size())
    for (std::size_t k = 0; k < bodies.size(); ++k) bodies[k].vel = m.bodyVel[k], bodies[k].angVel = m.bodyAngVel[k];
  restFlat_ = std::move(m.restFlat), restDir_ = std::move(m.restDir);
  if (!m.stats.empty()) stats = m.stats[0];
  pairsValid_ = false, pairsChanged_ = true;
  return true;
}

}  // namespace woven
