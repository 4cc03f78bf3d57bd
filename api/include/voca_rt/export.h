#pragma once
// VOCA_RT_API marks what the shared library exports; everything else in it stays private.

#if defined(VOCA_RT_BUILDING_LIBRARY)
#define VOCA_RT_API __attribute__((visibility("default")))
#else
#define VOCA_RT_API
#endif
