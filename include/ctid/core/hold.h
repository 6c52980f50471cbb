// How a sampled signal is continued between its samples: the one intersample assumption used
// by the simulators (ZOH/FOH inputs), the estimators' filters (measured input and output) and
// validation, so that every part of ctid that meets a sampled signal reads it the same way.
#pragma once

#include <array>
#include <span>

#include "ctid/core/fields.h"

namespace ctid {

enum class Hold {
  zero_order_hold,   ///< x(t) = x_k on [t_k, t_k+1): exact for inputs held by a DAC
  first_order_hold,  ///< x(t) linear between x_k and x_k+1 (held after the last sample)
};

inline constexpr std::array<Enumerator<Hold>, 2> hold_enumerators{{
    {Hold::zero_order_hold, "zero_order_hold", "Held constant between samples."},
    {Hold::first_order_hold, "first_order_hold", "Linear between samples."},
}};
constexpr std::span<const Enumerator<Hold>> enumerators(Hold) { return hold_enumerators; }

}  // namespace ctid
