// A section (core/fields.h) written to and read from YAML by its one description:
// the result file's blocks. Internal to io, as yaml_primitives.h.
#pragma once

#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "handeye_covariance/core/fields.h"
#include "handeye_covariance/core/pose_covariance.h"
#include "yaml_primitives.h"

namespace handeye {
namespace io {
namespace detail {

template <class T>
struct is_optional : std::false_type {};
template <class T>
struct is_optional<std::optional<T>> : std::true_type {};
template <class T>
struct is_vector : std::false_type {};
template <class T>
struct is_vector<std::vector<T>> : std::true_type {};

/// Whether a field holds something: a non-empty string or list, a true bool, a non-zero number.
template <class T>
bool holds_something(const T& value) {
  if constexpr (std::is_same_v<T, std::string> || is_vector<T>::value) {
    return !value.empty();
  } else if constexpr (std::is_arithmetic_v<T>) {
    return value != T{};
  } else {
    return true;
  }
}

template <class T>
bool is_written(const T&) {
  return true;
}
template <class T>
bool is_written(const T&, Only only) {
  return only.written;
}
template <class T>
bool is_written(const T& value, WhenSet) {
  return holds_something(value);
}
template <class T>
bool is_written(const T&, Optional) {
  return true;
}
template <class T>
bool is_written(const T&, InMemory) {
  return false;
}
template <class T>
bool is_written(const T&, Block) {
  return true;
}


/// Whether a reader needs the key: fields with no option, and Only's where it holds.
inline bool is_required() { return true; }
inline bool is_required(Only only) { return only.written && !only.optional; }
inline bool is_required(WhenSet) { return false; }
inline bool is_required(Optional) { return false; }
inline bool is_required(InMemory) { return false; }
inline bool is_required(Block) { return true; }

/// Whether a field is written: an optional only when set, then as its options say.
template <class T, class... Option>
bool written(const T& value, Option... option) {
  if constexpr (is_optional<T>::value) {
    return value.has_value() && is_written(*value, option...);
  } else {
    return is_written(value, option...);
  }
}

/// A fixed-size matrix's row-major twin (a column vector stays as it is).
template <int Rows, int Cols>
using RowMajorMatrix = Eigen::Matrix<double, Rows, Cols, (Cols == 1 ? Eigen::ColMajor : Eigen::RowMajor)>;

template <class T>
struct is_eigen_matrix : std::false_type {};
template <int Rows, int Cols, int Options>
struct is_eigen_matrix<Eigen::Matrix<double, Rows, Cols, Options>> : std::bool_constant<(Rows > 0 && Cols > 0)> {};

/// "{name, value, sigma}": a section's keys, for a reader's advice.
template <class S>
std::string keys_of() {
  std::string keys;
  S probe{};
  S::fields(probe, [&](const char* key, auto&&, auto... option) {
    if constexpr (!(std::is_same_v<decltype(option), InMemory> || ...)) keys += (keys.empty() ? "{" : ", ") + std::string(key);
  });
  return keys + "}";
}

template <class S>
void emit_section(YAML::Emitter& out, const S& section, bool flow);

template <class T>
void emit_value(YAML::Emitter& out, const T& value) {
  if constexpr (is_eigen_matrix<T>::value) {  // its numbers in one list, row-major (a Matrix6d's in ROS order)
    const RowMajorMatrix<T::RowsAtCompileTime, T::ColsAtCompileTime> rows = value;
    emit_numbers(out, rows.data(), static_cast<std::size_t>(rows.size()));
  } else if constexpr (std::is_same_v<T, PoseWithCovariance>) {  // the pose's keys and its covariance
    out << YAML::BeginMap;
    emit_pose(out, value.pose);
    out << YAML::Key << "covariance" << YAML::Value;
    emit_value(out, value.covariance);
    out << YAML::EndMap;
  } else if constexpr (std::is_same_v<T, std::vector<Eigen::Vector3d>>) {  // x, y, z of each, in one list
    std::vector<double> numbers;
    for (const Eigen::Vector3d& p : value) numbers.insert(numbers.end(), {p.x(), p.y(), p.z()});
    emit_numbers(out, numbers.data(), numbers.size());
  } else if constexpr (is_section_v<T>) {
    emit_section(out, value, true);
  } else if constexpr (is_vector<T>::value) {
    if constexpr (is_section_v<typename T::value_type>) {
      out << YAML::BeginSeq;
      for (const auto& element : value) emit_section(out, element, true);
      out << YAML::EndSeq;
    } else {
      out << YAML::Flow << value;
    }
  } else if constexpr (std::is_enum_v<T>) {
    out << to_string(value);
  } else {
    out << value;
  }
}

/// The section's fields as `key: value` pairs into the map `out` has open.
template <class S>
void emit_fields(YAML::Emitter& out, const S& section) {
  S::fields(section, [&](const char* key, const auto& member, auto... option) {
    if constexpr (!(std::is_same_v<decltype(option), InMemory> || ...)) {  // files do not carry an InMemory field
      if (!written(member, option...)) return;
      out << YAML::Key << key << YAML::Value;
      const auto& value = [&]() -> const auto& {
        if constexpr (is_optional<std::decay_t<decltype(member)>>::value) {
          return *member;
        } else {
          return member;
        }
      }();
      using T = std::decay_t<decltype(value)>;
      if constexpr (is_section_v<T> && (std::is_same_v<decltype(option), Block> || ...)) {
        emit_section(out, value, false);
      } else {
        emit_value(out, value);
      }
    }
  });
}

/// The section as a map (on one line when `flow`).
template <class S>
void emit_section(YAML::Emitter& out, const S& section, bool flow) {
  if (flow) out << YAML::Flow;
  out << YAML::BeginMap;
  emit_fields(out, section);
  out << YAML::EndMap;
}

template <class S>
void read_section(const YAML::Node& node, const Location& at, S& section);

template <class T>
void read_value(const YAML::Node& node, const Location& at, T& value) {
  if constexpr (std::is_same_v<T, Matrix6d>) {
    value = from_row_major_6x6(as_numbers<36>(node, at, "6x6, row-major, ROS order"));
  } else if constexpr (is_eigen_matrix<T>::value) {
    constexpr int rows = T::RowsAtCompileTime, cols = T::ColsAtCompileTime;
    const auto numbers = as_numbers<static_cast<std::size_t>(rows * cols)>(
        node, at, std::to_string(rows) + " x " + std::to_string(cols) + ", row-major");
    value = Eigen::Map<const RowMajorMatrix<rows, cols>>(numbers.data());
  } else if constexpr (std::is_same_v<T, PoseWithCovariance>) {
    if (!node.IsMap()) {
      throw HandEyeError(ErrorCode::MalformedFile, "expected a pose with its covariance", at.str(),
                         "write the pose's keys and `covariance` (36 numbers, row-major, ROS order)");
    }
    value.pose = read_pose(node, at);
    read_value(require(node, "covariance", at, "a pose here carries its `covariance` (36 numbers, row-major, ROS order)"),
               at / "covariance", value.covariance);
  } else if constexpr (std::is_same_v<T, std::vector<Eigen::Vector3d>>) {
    const std::vector<double> numbers = as_number_list(node, at, "x, y, z of each point");
    if (numbers.size() % 3 != 0) {
      throw HandEyeError(ErrorCode::WrongLength, "`" + at.path + "` needs 3 numbers per point", at.str(),
                         "write x, y, z of each point in one list");
    }
    value.clear();
    for (std::size_t i = 0; i + 2 < numbers.size(); i += 3) value.emplace_back(numbers[i], numbers[i + 1], numbers[i + 2]);
  } else if constexpr (is_section_v<T>) {
    read_section(node, at, value);
  } else if constexpr (is_vector<T>::value) {
    using Element = typename T::value_type;
    if (!node.IsSequence()) {
      throw HandEyeError(ErrorCode::MalformedFile, "expected a list", at.str(),
                         is_section_v<Element> ? "write one " + keys_of<Element>() + " per entry" : "write it as [a, b, ...]");
    }
    value.clear();
    for (std::size_t i = 0; i < node.size(); ++i) read_value(node[i], at[i], value.emplace_back());
  } else if constexpr (std::is_same_v<T, double>) {
    value = as_finite(node, at, "NaN or Inf in `" + at.path + "`", "write a finite number");
  } else if constexpr (std::is_same_v<T, int>) {
    value = as_integer(node, at, -1e9, 1e9, at.path);
  } else if constexpr (std::is_same_v<T, bool>) {
    value = as_bool(node, at);
  } else if constexpr (std::is_same_v<T, std::string>) {
    value = node.IsNull() ? std::string() : as_text(node, at);
  } else {
    static_assert(std::is_enum_v<T>, "a field type sections.h cannot read");
    value = from_string(as_text(node, at), T{});
  }
}

/// The section from the map `node`: a field without an option is required, and an
/// Only field where its condition holds on what was read before it (MissingKey naming
/// the section's keys); the others keep their default when absent.
template <class S>
void read_section(const YAML::Node& node, const Location& at, S& section) {
  if (!node.IsMap()) {
    throw HandEyeError(ErrorCode::MalformedFile, "expected a map", at.str(), "write it as " + keys_of<S>());
  }
  S::fields(section, [&](const char* key, auto& member, auto... option) {
    if constexpr (!(std::is_same_v<decltype(option), InMemory> || ...)) {  // files do not carry an InMemory field
      using T = std::decay_t<decltype(member)>;
      const YAML::Node child = node[key];
      if (!child) {
        if (!is_optional<T>::value && is_required(option...)) require(node, key, at, "it is " + keys_of<S>());
        return;
      }
      if constexpr (is_optional<T>::value) {
        read_value(child, at / key, member.emplace());
      } else {
        read_value(child, at / key, member);
      }
    }
  });
}

}  // namespace detail
}  // namespace io
}  // namespace handeye
