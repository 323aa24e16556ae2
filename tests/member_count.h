// The tests' count of an options struct's members against its table's rows
// (femreg/field_table.h): a member added to a struct but not to its table changes it.
#ifndef FEMREG_TESTS_MEMBER_COUNT_H_
#define FEMREG_TESTS_MEMBER_COUNT_H_

#include <cstddef>
#include <type_traits>
#include <utility>

#include "femreg/field_table.h"

namespace femreg {
namespace testing_tables {

// The number of members of an aggregate: the longest brace list of AnyValue that
// initializes it.
struct AnyValue {
  template <class T>
  constexpr operator T() const {  // NOLINT: converts to whatever member it initializes
    return T{};
  }
};
template <class T, class... A>
auto Initializes(int) -> decltype(T{std::declval<A>()...}, std::true_type{});
template <class T, class... A>
std::false_type Initializes(...);
template <class T, class... A>
constexpr std::size_t MemberCount() {
  if constexpr (decltype(Initializes<T, A..., AnyValue>(0))::value) {
    return MemberCount<T, A..., AnyValue>();
  } else {
    return sizeof...(A);
  }
}

// The rows of S's table.
template <class Options>
std::size_t FieldCount() {
  std::size_t n = 0;
  OptionFields<Options>::Visit([&](auto, const FieldInfo&) { ++n; });
  return n;
}

}  // namespace testing_tables
}  // namespace femreg

#endif  // FEMREG_TESTS_MEMBER_COUNT_H_
