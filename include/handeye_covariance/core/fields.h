// A section's fields, described once. A section (a struct of a result) declares
//   template <class Self, class Visit> static void fields(Self& self, Visit&& visit)
// calling visit(key, self.member) for each field, in the order files list them, and
// visit(key, self.member, option) where a field is optional (below). `Self` is the
// section, const or not, so the one description serves writers and readers alike.
// The YAML writer and reader (src/io/sections.h) walk it, and test_sections checks
// that it names every field the struct has (no byte of the struct left out).
// Field types: double, int, bool, std::string, an enum with to_string (and, to be
// read, from_string(text, E{})), a fixed-size Eigen matrix of doubles (its numbers in
// one list, row-major: Matrix6d's 36 in ROS order), a list of Eigen::Vector3d (3 numbers
// each, in one list), a PoseWithCovariance (the pose's keys and `covariance`, 36
// numbers), a section, std::vector of a section, and std::optional of a section
// (written when set, optional when read).
#pragma once

#include <type_traits>
#include <utility>

namespace handeye {

/// A field that is written only where `written` holds, and required when read where it
/// holds (evaluated on what was read before it: write the condition inline, on fields
/// described earlier); elsewhere absent, it keeps its default. `optional`: never required
/// (files of earlier versions lack it). Fields without options are always written and
/// required when read.
struct Only {
  bool written = true;
  bool optional = false;
};
/// A field written only when it holds something (a non-empty string or list, a
/// true bool, a non-zero number) and optional when read.
inline constexpr struct WhenSet {
} kWhenSet{};
/// A field always written but optional when read (files of earlier versions lack it).
inline constexpr struct Optional {
} kOptional{};
/// A field that files do not carry: kept in memory for the program that made it.
inline constexpr struct InMemory {
} kInMemory{};
/// A section field written as an indented map rather than on one line.
inline constexpr struct Block {
} kBlock{};

/// A visitor that takes any field: what is_section probes with.
struct AnyField {
  template <class... Arguments>
  void operator()(const char*, Arguments&&...) const {}
};
/// Whether T describes its fields.
template <class T, class = void>
struct is_section : std::false_type {};
template <class T>
struct is_section<T, std::void_t<decltype(T::fields(std::declval<T&>(), AnyField{}))>> : std::true_type {};
template <class T>
inline constexpr bool is_section_v = is_section<std::decay_t<T>>::value;

}  // namespace handeye
