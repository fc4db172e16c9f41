// std::bit_cast, which the libc++ of Debian's emscripten (3.1.6) lacks: the browser build compiles the
// codecs too. gcc and clang both provide the builtin the standard one is made of.
#pragma once
#include <type_traits>

namespace pms {

template <class To, class From>
constexpr To bit_cast(const From& from) noexcept {
  static_assert(sizeof(To) == sizeof(From), "bit_cast between types of different sizes");
  static_assert(std::is_trivially_copyable_v<To> && std::is_trivially_copyable_v<From>);
  return __builtin_bit_cast(To, from);
}

}  // namespace pms
