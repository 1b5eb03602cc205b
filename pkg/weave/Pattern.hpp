// Interlacing matrix of a weave: entry (i, j) = 1 where warp yarn i passes over weft yarn j.
// The matrix is one repeat (unit cell) of the weave.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace woven {

class Pattern {
 public:
  /// rows = warp yarns of the repeat, cols = weft yarns; values 0/1. Throws ParameterError
  /// ("pattern") if empty, ragged, not 0/1, or if some yarn never interlaces (all over or all under).
  explicit Pattern(std::vector<std::vector<int>> matrix);

  static Pattern plain();
  /// Twill n/m: each warp goes over n wefts then under m, shifted by one weft per warp (n, m >= 1).
  static Pattern twill(int over, int under);
  /// Satin with `n` harnesses (n >= 5) and move `step` (1 < step < n-1, coprime with n): warp i is
  /// over weft (i*step) mod n only (warp-faced satin floats).
  static Pattern satin(int n, int step);
  /// Basket (matt) weave n: plain weave with every yarn doubled (n >= 1; n = 1 is plain).
  static Pattern basket(int n);
  /// By name: "plain", "twill", "satin", "basket" with their integer parameters.
  static Pattern byName(const std::string& name, int a = 2, int b = 1);

  int rows() const { return static_cast<int>(m_.size()); }     ///< warp yarns in the repeat
  int cols() const { return static_cast<int>(m_[0].size()); }  ///< weft yarns in the repeat
  bool warpOver(int i, int j) const { return m_[i][j] != 0; }  ///< warp i over weft j
  const std::vector<std::vector<int>>& matrix() const { return m_; }

 private:
  std::vector<std::vector<int>> m_;
};

}  // namespace woven
