#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace gpucol {

/// What the contact reduction looks at of one contact (the frame does not matter, as long as all
/// contacts of one call share it).
struct ReductionInput {
  Eigen::Vector3f point;   ///< Contact point.
  Eigen::Vector3f normal;  ///< Unit contact normal (components in [-1, 1]).
  float depth;             ///< Signed depth, negative when penetrating: the most negative is the deepest.
};

/// 6-D binning (thesis §5.3.5): returns the indices of the kept contacts, ascending; resolution 0 keeps all.
///
/// Each contact goes to the bin floor(x * resolution) (clamped to resolution - 1) in each of six
/// dimensions: its position scaled into the unit cube of all the contacts' bounding box (an axis of zero
/// extent maps to 0), and its normal mapped from [-1, 1] to [0, 1]. Each occupied bin keeps one contact:
/// the deepest, ties to the lowest index. So at most resolution^6 contacts survive, the deepest contact
/// always does, and the same input always gives the same indices. The thesis keeps the contact farthest
/// from the cube's origin instead; see contact_reduction.cpp for why we keep the deepest.
/// Throws std::invalid_argument for a negative resolution and for a NaN or infinite value (naming the
/// contact's index), which could not be binned.
std::vector<std::uint32_t> reduceContacts(const std::vector<ReductionInput>& contacts, int resolution);

}  // namespace gpucol
