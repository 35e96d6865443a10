#pragma once
// Options given twice (internal): refused with the parameter's name.
#include <algorithm>
#include <cmath>
#include <corrlap/core/error.hpp>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace corrlap::detail {

// A value given twice would compute the same unit twice: duplicated rows, and a spread over
// "centres" that are copies of one another.
template <class T>
inline void refuse_repeats(const std::vector<T>& values, const std::string& what, const std::string& parameter,
                           const std::string& study) {
  for (std::size_t i = 0; i < values.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) {
      bool same;
      if constexpr (std::is_floating_point_v<T>)
        same = std::abs(values[i] - values[j]) <= 1e-12 * std::max(std::abs(values[i]), std::abs(values[j]));
      else
        same = values[i] == values[j];
      if (!same) continue;
      std::ostringstream os;
      os << study << ": " << what << " " << values[i] << " is given twice; give each once";
      throw InputError(os.str(), parameter);
    }
}

}  // namespace corrlap::detail
