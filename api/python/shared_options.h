// The keyword arguments voca.Odometry and voca.run both take: the command line's options of the same
// names. One table owns their names, conversions, defaults (voca_rt::Options' own) and descriptions;
// both functions read them from their **options and both docstrings list them from it.
#pragma once

#include <pybind11/pybind11.h>

#include <string>

#include "voca_rt/odometry.h"

namespace voca_python {

// Sets the named option from a Python value; None leaves the option at its default. Raises
// TypeError naming the function and the option for an unknown name or a value of the wrong type.
void setSharedOption(voca_rt::Options& options, const std::string& name, const pybind11::handle& value,
                     const char* function);

// Every keyword argument of `keywords` as a shared option (see setSharedOption).
void setSharedOptions(voca_rt::Options& options, const pybind11::kwargs& keywords, const char* function);

// The docstring section listing each shared option with its default and what it does.
std::string sharedOptionsDoc();

}  // namespace voca_python
