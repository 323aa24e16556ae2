// The tests' helpers for the options tables (femreg/field_table.h): the count of a struct's
// members against its table's rows (a member added to a struct but not to its table changes
// it), two structs compared field by field, and a value other than a field's default.
#ifndef FEMREG_TESTS_MEMBER_COUNT_H_
#define FEMREG_TESTS_MEMBER_COUNT_H_

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cstddef>
#include <optional>
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
    if constexpr (FieldType<T>::kOptional) {  // both unset, or both set to the same value
      EXPECT_EQ((a.*member).has_value(), (b.*member).has_value()) << f.key << " after " << when;
      EXPECT_TRUE(a.*member == b.*member) << f.key << " after " << when;
    } else if constexpr (std::is_enum_v<T>) {
      EXPECT_STREQ(ToString(a.*member), ToString(b.*member)) << f.key << " after " << when;
    } else {
      EXPECT_EQ(a.*member, b.*member) << f.key << " after " << when;
    }
  });
}

// A value other than `d` that the field's range allows: a flag flipped, the next enum value,
// a vector moved (a box's min down, else up; an unbounded default such as a crop's +-1e30 to
// zero), a number one larger (or one smaller for an integer, or halfway to an upper bound that
// one larger would pass). An optional left unset gets its type's zero (the first enum value,
// 0) where the range allows it, else the value other than that; one set is unset.
template <class T>
T OtherValue(const FieldInfo& f, T d) {
  if constexpr (FieldType<T>::kOptional) {
    using V = typename FieldType<T>::Value;
    if (d.has_value()) return T();
    const V zero{};
    if constexpr (std::is_arithmetic_v<V>) {
      if (!f.InRange(static_cast<double>(zero))) return OtherValue(f, zero);
    }
    return zero;
  } else if constexpr (std::is_same_v<T, bool>) {
    return !d;
  } else if constexpr (std::is_enum_v<T>) {
    const auto& all = EnumValues<T>::kAll;
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (all[i] == d) return all[(i + 1) % all.size()];
    }
    return d;
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    const Eigen::Vector3d step(1, 2, 3);
    const Eigen::Vector3d v = std::string(f.key) == "min" ? Eigen::Vector3d(d - step) : Eigen::Vector3d(d + step);
    return v != d ? v : Eigen::Vector3d::Zero();
  } else {
    static_assert(std::is_arithmetic_v<T>, "the tables hold flags, enums, vectors and numbers");
    T v = d + 1;
    if (!f.InRange(static_cast<double>(v))) {
      v = std::is_integral_v<T> ? static_cast<T>(d - 1) : static_cast<T>((d + f.max) / 2);
    }
    return v;
  }
}

}  // namespace testing_tables
}  // namespace femreg

#endif  // FEMREG_TESTS_MEMBER_COUNT_H_
