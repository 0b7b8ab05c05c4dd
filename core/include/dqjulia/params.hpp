// dqjulia/params.hpp - the parameter set and its file, for code that uses all of it:
//   param_types.hpp  the values and their defaults     keyframes.hpp  the "animation" section
//   param_file.hpp   reading, validating and writing   schema.hpp     every key described once
#pragma once

#include "dqjulia/keyframes.hpp"
#include "dqjulia/param_file.hpp"
#include "dqjulia/param_types.hpp"
#include "dqjulia/schema.hpp"
