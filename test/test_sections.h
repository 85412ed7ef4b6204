// Checks every section (core/fields.h) against its description: the description names
// every field of the struct (no byte left out), and a section written and read back is
// the same, field by field (each field it writes). Used by test_yaml_io.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "handeye_covariance/core/fields.h"
#include "handeye_covariance/core/pose_covariance.h"
#include "sections.h"

namespace handeye {
namespace test {

/// The bytes of S that its description leaves out: a member spans [offset, offset +
/// size); between consecutive spans, and after the last, only padding may lie (less
/// than the next member's, or the struct's, alignment). Empty when every field is described.
template <class S>
std::vector<std::string> undescribed(const S& probe) {
  struct Span {
    std::size_t begin, end, align;
    std::string key;
  };
  std::vector<Span> spans;
  const char* base = reinterpret_cast<const char*>(&probe);
  S::fields(probe, [&](const char* key, const auto& member, auto&&...) {
    const std::size_t begin = static_cast<std::size_t>(reinterpret_cast<const char*>(&member) - base);
    spans.push_back({begin, begin + sizeof(member), alignof(std::decay_t<decltype(member)>), key});
  });
  std::sort(spans.begin(), spans.end(), [](const Span& a, const Span& b) { return a.begin < b.begin; });
  std::vector<std::string> gaps;
  std::size_t covered = 0;
  for (const Span& s : spans) {
    if (s.begin < covered) gaps.push_back("`" + s.key + "` described twice or overlapping");
    if (s.begin >= covered + s.align) {
      gaps.push_back(std::to_string(s.begin - covered) + " undescribed bytes before `" + s.key + "`");
    }
    covered = std::max(covered, s.end);
  }
  if (sizeof(S) >= covered + alignof(S)) gaps.push_back(std::to_string(sizeof(S) - covered) + " undescribed bytes at the end");
  return gaps;
}

/// Each field set to a value of its own (numbers by position, strings by key, bools true,
/// lists of one such section), so that a round trip that drops or swaps one shows.
struct Fill {
  int counter = 0;
  static Matrix6d spd(int counter) {
    const Matrix6d A = Matrix6d::Identity() + 0.01 * counter * Matrix6d::Ones();
    return A * A.transpose();
  }
  template <class T, class... Option>
  void operator()(const char* key, T& member, Option&&...) {
    ++counter;
    if constexpr (std::is_same_v<T, double>) {
      member = counter + 0.25;
    } else if constexpr (std::is_same_v<T, int>) {
      member = counter + 1;
    } else if constexpr (std::is_same_v<T, bool>) {
      member = true;
    } else if constexpr (std::is_same_v<T, std::string>) {
      member = std::string(key) + " text";
    } else if constexpr (std::is_same_v<T, Matrix6d>) {  // symmetric positive definite, every entry its own
      member = spd(counter);
    } else if constexpr (io::detail::is_eigen_matrix<T>::value) {
      for (int k = 0; k < member.size(); ++k) member(k) = counter + 0.01 * k;
    } else if constexpr (std::is_same_v<T, PoseWithCovariance>) {
      member.pose = Eigen::Translation3d(0.1 * counter, 0.2, 0.3) * Eigen::AngleAxisd(0.1 * counter, Eigen::Vector3d(1, 2, 3).normalized());
      member.covariance = spd(counter);
    } else if constexpr (std::is_same_v<T, std::vector<Eigen::Vector3d>>) {
      member = {Eigen::Vector3d(counter, counter + 0.5, counter + 0.75)};
    } else if constexpr (std::is_enum_v<T>) {
      member = T{};  // its first value, which no section has as its default
    } else if constexpr (is_section_v<T>) {
      T::fields(member, *this);
    } else if constexpr (io::detail::is_optional<T>::value) {
      T::value_type::fields(member.emplace(), *this);
    } else if constexpr (std::is_same_v<T, std::vector<typename T::value_type>>) {
      member.resize(1);
      if constexpr (is_section_v<typename T::value_type>) T::value_type::fields(member[0], *this);
    }
  }
};

/// The section's written fields as "key=value" lines, nested sections and lists
/// included: a field its description says is not written (io/sections.h written,
/// e.g. one of two exclusive keys) is left out.
struct Flatten {
  std::vector<std::string> lines;
  std::string prefix;
  template <class T, class... Option>
  void operator()(const char* key, const T& member, Option... option) {
    if (!io::detail::written(member, option...)) return;
    const std::string name = prefix + key;
    char text[64];
    if constexpr (std::is_same_v<T, double>) {
      std::snprintf(text, sizeof(text), "%.17g", member);
      lines.push_back(name + "=" + text);
    } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, bool>) {
      lines.push_back(name + "=" + std::to_string(member));
    } else if constexpr (std::is_same_v<T, std::string>) {
      lines.push_back(name + "=" + member);
    } else if constexpr (std::is_enum_v<T>) {
      lines.push_back(name + "=" + std::to_string(static_cast<int>(member)));
    } else if constexpr (std::is_same_v<T, PoseWithCovariance>) {  // the pose to 12 digits: it is written as a quaternion
      for (int k = 0; k < 16; ++k) {
        std::snprintf(text, sizeof(text), "%.12g", member.pose.matrix()(k) + 0.0);
        lines.push_back(name + ".pose=" + text);
      }
      const std::string outer = prefix;
      prefix = name + ".";
      (*this)("covariance", member.covariance);
      prefix = outer;
    } else if constexpr (io::detail::is_eigen_matrix<T>::value || std::is_same_v<T, std::vector<Eigen::Vector3d>>) {
      std::vector<double> numbers;
      if constexpr (io::detail::is_eigen_matrix<T>::value) {
        numbers.assign(member.data(), member.data() + member.size());
      } else {
        for (const Eigen::Vector3d& p : member) numbers.insert(numbers.end(), {p.x(), p.y(), p.z()});
      }
      for (double v : numbers) {
        std::snprintf(text, sizeof(text), "%.17g", v);
        lines.push_back(name + "=" + text);
      }
    } else if constexpr (is_section_v<T>) {
      const std::string outer = prefix;
      prefix = name + ".";
      T::fields(member, *this);
      prefix = outer;
    } else if constexpr (io::detail::is_optional<T>::value) {
      (*this)(key, *member);
    } else {
      lines.push_back(name + " entries=" + std::to_string(member.size()));
      const std::string outer = prefix;
      for (std::size_t i = 0; i < member.size(); ++i) {
        prefix = name + "[" + std::to_string(i) + "].";
        if constexpr (is_section_v<typename T::value_type>) {
          T::value_type::fields(member[i], *this);
        } else {
          lines.push_back(prefix + "value=" + std::to_string(member[i]));
        }
      }
      prefix = outer;
    }
  }
};

template <class S>
std::vector<std::string> flattened(const S& section) {
  Flatten f;
  S::fields(section, f);
  return f.lines;
}

template <class S>
S filled() {
  S section{};
  Fill fill;
  S::fields(section, fill);
  return section;
}

}  // namespace test
}  // namespace handeye
