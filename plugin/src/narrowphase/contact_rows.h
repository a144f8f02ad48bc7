#pragma once
// generateContactAndTest over many pairs at once, for the near phase's pairs that its float pre-tests could
// not reject (thesis §5.3.4). One pair at a time, the double test is a chain of dependent divisions and
// square roots behind early returns and a handful of branches whose outcome is a coin toss (which vertex is
// alone on its side, which crossing comes first, which triangle moves). Here every step runs for four pairs at
// once, one per lane of a vector of doubles, and the answers are chosen by masks: no branch depends on a pair,
// and one vector division or square root serves four pairs. Written with GCC/Clang vector extensions, since
// GCC 12 did not vectorise the same steps written per pair (measurement history).
//
// Same operations in the same order as generateContactAndTest (Eigen's 3-vector dot products and norms sum
// (x + y) + z), so every output is the same bits; coplanar pairs, which need the 2-D overlap test, and pairs
// with a non-finite coordinate are only flagged and left to it.

#include <cstddef>
#include <cstdint>

namespace gpucol::detail {

/// What generateContactRows found for one pair.
enum ContactRowOutcome : std::uint32_t {
  kRowApart = 0,            ///< no intersection (or a degenerate triangle)
  kRowIntersectsNoContact,  ///< intersecting, contact dropped (they slide apart by less than the depth)
  kRowContact,              ///< intersecting, with the contact in the output rows
  kRowOnePair,              ///< coplanar (or a non-finite coordinate): call generateContactAndTest
};

/// Flags of ContactRowOutcome's word, above its two low bits.
constexpr std::uint32_t kRowOutcomeMask = 3;
constexpr std::uint32_t kRowOnFaceOfB = 4;   ///< TriangleContact::onFaceOfB
constexpr std::uint32_t kRowSameFacing = 8;  ///< TriangleContact::sameFacing

/// Rows of the contacts, kContactRowValues values per pair, value k of pair t at [k * stride + t]: point
/// x y z (0-2), normalOnB x y z (3-5), depth (6), deepestPoint x y z (7-9).
constexpr std::size_t kContactRowValues = 10;

/// The double test and contact of generateContactAndTest for `count` pairs. `triangles` holds 18 rows at
/// `stride` floats: value k of pair t at [k * stride + t], A's vertices x y z (k = 0..8) then B's (9..17),
/// in the frame the contact is wanted in. Writes `outcome[t]` (ContactRowOutcome, with the flags) for every
/// pair, and `contacts` (kContactRowValues rows at `stride`) where the outcome is kRowContact.
void generateContactRows(const float* triangles, std::size_t stride, std::size_t count, float* contacts,
                         std::uint32_t* outcome);

}  // namespace gpucol::detail
