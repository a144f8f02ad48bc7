#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace gpucol {

/// How reading one word of a text mesh file as a number ended.
enum class NumberStatus {
  kOk,            ///< The whole word is the number, and it is in range.
  kNotANumber,    ///< Not a decimal number at all ("zero", "0x10", "1e", "").
  kNotAnInteger,  ///< A decimal number where an integer is required ("2.5", "1e3").
  kOutOfRange,    ///< A number beyond the range asked for (or beyond double).
  kNotFinite,     ///< "inf" or "nan".
};

/// Reads the whole of `word` as a decimal integer in [min, max], exactly: no rounding, no wrapping, no
/// partial reads. One leading '+' is allowed. `value` is set only on kOk.
NumberStatus parseInteger(std::string_view word, std::int64_t min, std::int64_t max, std::int64_t& value);

/// Reads the whole of `word` as a finite decimal number (no hexadecimal, no "inf" or "nan"), rounded once to
/// the nearest double. One leading '+' is allowed. `value` is set only on kOk.
NumberStatus parseReal(std::string_view word, double& value);

/// Why a word was refused, for an error message: "is not a number", "is not an integer", "is out of range",
/// "is not finite"; `range` describes the range for kOutOfRange (e.g. "for uchar (0 to 255)").
std::string numberProblem(NumberStatus status, const std::string& range = std::string());

}  // namespace gpucol
