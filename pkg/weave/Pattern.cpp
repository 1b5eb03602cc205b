#include "weave/Pattern.hpp"
#include "core/Errors.hpp"
#include <numeric>

namespace woven {

Pattern::Pattern(std::vector<std::vector<int>> m) : m_(std::move(m)) {
  if (m_.empty() || m_[0].empty())
    throw ParameterError("pattern", "empty matrix", "a non-empty 0/1 interlacing matrix");
  const std::size_t nc = m_[0].size();
  for (std::size_t i = 0; i < m_.size(); ++i) {
    if (m_[i].size() != nc)
      throw ParameterError("pattern", "row " + fmt(i) + " has " + fmt(m_[i].size()) + " entries",
                           "every row with " + fmt(nc) + " entries");
    for (int v : m_[i])
      if (v != 0 && v != 1) throw ParameterError("pattern", "entry " + fmt(v), "entries 0 or 1");
  }
  for (std::size_t i = 0; i < m_.size(); ++i) {
    const int s = std::accumulate(m_[i].begin(), m_[i].end(), 0);
    if (s == 0 || s == static_cast<int>(nc))
      throw ParameterError("pattern", "warp " + fmt(i) + " never interlaces",
                           "every warp row with both 0 and 1 entries");
  }
  for (std::size_t j = 0; j < nc; ++j) {
    int s = 0;
    for (const auto& r : m_) s += r[j];
    if (s == 0 || s == static_cast<int>(m_.size()))
      throw ParameterError("pattern", "weft " + fmt(j) + " never interlaces",
                           "every weft column with both 0 and 1 entries");
  }
}

Pattern Pattern::plain() { return Pattern({{1, 0}, {0, 1}}); }

Pattern Pattern::twill(int over, int under) {
  require(over >= 1 && over <= 16, "twill_over", over, "[1, 16]");
  require(under >= 1 && under <= 16, "twill_under", under, "[1, 16]");
  const int n = over + under;
  std::vector<std::vector<int>> m(n, std::vector<int>(n, 0));
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < over; ++k) m[i][(i + k) % n] = 1;
  return Pattern(m);
}

Pattern Pattern::satin(int n, int step) {
  require(n >= 5 && n <= 32, "satin_n", n, "[5, 32]");
  require(step > 1 && step < n - 1 && std::gcd(n, step) == 1, "satin_step", step,
          "1 < step < n-1 and coprime with n");
  std::vector<std::vector<int>> m(n, std::vector<int>(n, 0));
  for (int i = 0; i < n; ++i) m[i][(i * step) % n] = 1;
  return Pattern(m);
}

Pattern Pattern::basket(int n) {
  require(n >= 1 && n <= 16, "basket_n", n, "[1, 16]");
  const int s = 2 * n;
  std::vector<std::vector<int>> m(s, std::vector<int>(s, 0));
  for (int i = 0; i < s; ++i)
    for (int j = 0; j < s; ++j) m[i][j] = ((i / n) + (j / n)) % 2 == 0 ? 1 : 0;
  return Pattern(m);
}

Pattern Pattern::byName(const std::string& name, int a, int b) {
  if (name == "plain") return plain();
  if (name == "twill") return twill(a, b);
  if (name == "satin") return satin(a, b);
  if (name == "basket") return basket(a);
  throw ParameterError("pattern", "'" + name + "'", "one of plain, twill, satin, basket, or a 0/1 matrix");
}

}  // namespace woven
