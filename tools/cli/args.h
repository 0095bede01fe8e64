// The CLI's name for the shared strict command-line parser, which lives in rtos_shim/args.h so
// the robot image (kuavo_fw) and kuavo_fw_sim use the same one without linking tools/.
#pragma once

#include "rtos_shim/args.h"

namespace kuavo::cli {

using args::check_input_file;
using args::check_output_file;
using args::parse_integer;
using args::parse_number;
using args::parse_uint64;

}  // namespace kuavo::cli
