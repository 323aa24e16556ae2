// The tests' helpers for the options tables (femreg/field_table.h): the count of a struct's
// members against its table's rows (a member added to a struct but not to its table changes
// it), and two structs compared field by field.
#ifndef FEMREG_TESTS_MEMBER_COUNT_H_
#define FEMREG_TESTS_MEMBER_COUNT_H_

#include <gtest/gtest.h>

#include <cstddef>
#include <string>
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

// Every field of a table equal in `a` and `b` (enums by name), each failure naming the field
// and `when`.
template <class Options>
void ExpectSameFields(const Options& a, const Options& b, const std::string& when) {
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    using T = std::decay_t<decltype(a.*member)>;
    if constexpr (std::is_enum_v<T>) {
      EXPECT_STREQ(ToString(a.*member), ToString(b.*member)) << f.key << " after " << when;
    } else {
      EXPECT_EQ(a.*member, b.*member) << f.key << " after " << when;
    }
  });
}

}  // namespace testing_tables
}  // namespace femreg

#endif  // FEMREG_TESTS_MEMBER_COUNT_H_
