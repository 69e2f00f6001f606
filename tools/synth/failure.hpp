// The one way mvod-synth reports a problem: a one-line message and an exit status.
#pragma once

#include <stdexcept>
#include <string>

namespace synth {

constexpr int kExitFailure = 1; // something went wrong at run time (unreadable or unwritable file)
constexpr int kExitUsage = 2;   // the command line asks for something impossible

struct Failure : std::runtime_error {
	Failure(int exit_status, const std::string &message) : std::runtime_error(message), status(exit_status) {}
	int status;
};

} // namespace synth
