// Doubles parsed from text exactly as std::from_chars does (chars_format::general, round to nearest),
// with a fast path for the plain decimals mesh files hold ("-0.0123456", "12.5e-3").
#pragma once

#include <charconv>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace retarget {

namespace parse_double_detail {

inline bool is_digit(char c) { return static_cast<unsigned>(c - '0') < 10; }

// 10^k for k in [0, 22]: every one is exact in a double.
inline double exact_power_of_ten(int k) {
  static constexpr double kPowers[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                       1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  return kPowers[k];
}

// A number of the form [-]digits[.digits][(e|E)[+|-]digits] whose significant digits fit in 15
// and whose decimal exponent lies in [-22, 22]: then the mantissa and the power of ten are exact
// doubles, and one product or quotient rounds the value correctly (Clinger's fast path), so it is
// bit for bit what from_chars gives, ending where from_chars stops (at whatever byte follows, as
// from_chars reads the longest such prefix too). Returns the end of the number, or nullptr for
// anything else (the caller then asks from_chars).
inline const char* parse_plain_decimal(const char* p, const char* last, double& value) {
#if defined(__SSE2__)
  // Only numbers of up to 11 bytes take this path ("-0.123456", "11.8387"). Longer ones, and
  // full-precision ones above all ("-2.3366602336660005", as to_chars writes doubles), go
  // straight to from_chars, whose 8-digits-at-a-time reading is faster there than this loop
  // (measured on such a file, the reader's time: +30% reading every number here first, +7% with
  // a 16-byte limit).
  if (last - p >= 16) {
    const __m128i bytes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
    const __m128i ends = _mm_or_si128(_mm_cmplt_epi8(bytes, _mm_set1_epi8('!')),  // blanks, controls, >= 0x80
                                      _mm_cmpeq_epi8(bytes, _mm_set1_epi8('#')));
    if ((_mm_movemask_epi8(ends) & 0xFFF) == 0) return nullptr;  // no end in the first 12 bytes
  }
#endif
  const bool negative = p != last && *p == '-';
  if (negative) ++p;
  std::uint64_t mantissa = 0;
  int significant = 0, exponent = 0;
  const char* digits = p;
  for (; p != last && is_digit(*p); ++p) {
    mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
    significant += significant > 0 || mantissa > 0;
    if (significant > 15) return nullptr;  // 16 digits or more may pass 2^53: from_chars
  }
  const bool integer_digits = p != digits;
  if (p != last && *p == '.') {
    const char* fraction = ++p;
    for (; p != last && is_digit(*p); ++p) {
      mantissa = mantissa * 10 + static_cast<unsigned>(*p - '0');
      significant += significant > 0 || mantissa > 0;
      if (significant > 15) return nullptr;
    }
    if (p == fraction) return nullptr;  // "1." and "-." go to from_chars
    exponent = -static_cast<int>(p - fraction);
  }
  if (!integer_digits) return nullptr;  // ".5", "-" and "inf" go to from_chars
  if (p != last && (*p == 'e' || *p == 'E')) {
    ++p;
    const bool negative_exponent = p != last && *p == '-';
    if (p != last && (*p == '-' || *p == '+')) ++p;
    const char* exponent_digits = p;
    int written = 0;
    for (; p != last && is_digit(*p) && p - exponent_digits < 4; ++p) written = written * 10 + (*p - '0');
    if (p == exponent_digits || (p != last && is_digit(*p))) return nullptr;
    exponent += negative_exponent ? -written : written;
  }
  if (exponent < -22 || exponent > 22) return nullptr;
  const double m = static_cast<double>(mantissa);
  const double magnitude = exponent >= 0 ? m * exact_power_of_ten(exponent) : m / exact_power_of_ten(-exponent);
  value = negative ? -magnitude : magnitude;
  return p;
}

}  // namespace parse_double_detail

// std::from_chars(first, last, value) for a double: the same value, end and error in every case
// (a leading '+' is refused as there); plain decimals of up to 15 significant digits take the fast
// path (numbers of up to 11 bytes), the rest from_chars itself. 2026-11-29, the 2-core AMD EPYC,
// one thread, four alternated rounds against from_chars alone: BM_ReadObj (the ICT face, 6-digit
// numbers) 1.13-1.14 -> 1.03-1.06 ms; BM_ReadObjWritten (17-digit numbers, as write_mesh writes
// them) 1.36-1.41 -> 1.39-1.45 ms, within the noise.
inline std::from_chars_result parse_double(const char* first, const char* last, double& value) {
  if (const char* end = parse_double_detail::parse_plain_decimal(first, last, value)) return {end, std::errc()};
  return std::from_chars(first, last, value);
}

}  // namespace retarget
