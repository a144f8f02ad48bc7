#include "mesh/strict_number.h"

#include <charconv>
#include <cmath>
#include <system_error>

namespace gpucol {

namespace {

/// The word without one leading '+', which from_chars does not take; empty when the '+' is all there is
/// or another sign follows it (so "+-1" is no number).
std::string_view withoutPlus(std::string_view word) {
  if (word.empty() || word[0] != '+') return word;
  word.remove_prefix(1);
  if (word.empty() || word[0] == '+' || word[0] == '-') return std::string_view();
  return word;
}

}  // namespace

NumberStatus parseInteger(std::string_view word, std::int64_t min, std::int64_t max, std::int64_t& value) {
  const std::string_view digits = withoutPlus(word);
  if (digits.empty()) return NumberStatus::kNotANumber;
  std::int64_t parsed = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), parsed);
  if (error == std::errc() && end == digits.data() + digits.size()) {
    if (parsed < min || parsed > max) return NumberStatus::kOutOfRange;
    value = parsed;
    return NumberStatus::kOk;
  }
  // Say what the word is instead: an integer beyond 64 bits, or a number that is not an integer.
  if (error == std::errc::result_out_of_range && end == digits.data() + digits.size())
    return NumberStatus::kOutOfRange;
  double real = 0;
  const NumberStatus asReal = parseReal(word, real);
  return asReal == NumberStatus::kNotANumber ? NumberStatus::kNotANumber : NumberStatus::kNotAnInteger;
}

NumberStatus parseReal(std::string_view word, double& value) {
  const std::string_view digits = withoutPlus(word);
  if (digits.empty()) return NumberStatus::kNotANumber;
  // chars_format::general: decimal and scientific only, so "0x10" stops after the '0' and is refused below.
  double parsed = 0;
  const auto [end, error] =
      std::from_chars(digits.data(), digits.data() + digits.size(), parsed, std::chars_format::general);
  if (end != digits.data() + digits.size() ||
      (error != std::errc() && error != std::errc::result_out_of_range))
    return NumberStatus::kNotANumber;
  if (error == std::errc::result_out_of_range) return NumberStatus::kOutOfRange;
  if (!std::isfinite(parsed)) return NumberStatus::kNotFinite;
  value = parsed;
  return NumberStatus::kOk;
}

std::string numberProblem(NumberStatus status, const std::string& range) {
  switch (status) {
    case NumberStatus::kOk:
      return "is a number";
    case NumberStatus::kNotANumber:
      return "is not a decimal number";
    case NumberStatus::kNotAnInteger:
      return "is not an integer";
    case NumberStatus::kOutOfRange:
      return range.empty() ? "is out of range" : "is out of range " + range;
    case NumberStatus::kNotFinite:
      return "is not finite";
  }
  return "is not a number";
}

}  // namespace gpucol
