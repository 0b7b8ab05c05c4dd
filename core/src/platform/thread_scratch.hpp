// thread_scratch.hpp - scratch objects for the threads of one parallel call (the SIMD kernels'
// batches, the renderer's ray lists): each thread that runs items of the call gets its own object,
// reused for every item it runs, and all of them are freed when the call's owner of the
// ThreadScratch is destroyed, by the thread that made it.
//
// Internal to libdqjulia. Why not `thread_local`: with MinGW-w64 (the Windows build), GCC's emulated
// TLS may free a thread's storage before the destructors of its thread_local objects run when the
// thread ends (GCC bug 80816), so a thread_local with a destructor corrupts the heap whenever a
// thread that used one exits: parallelForWithProgress's waiting thread does after every call, and
// so may a host's worker thread (Blender's bake jobs). Costs a lookup by thread id per `local()`.
#pragma once

#if defined(_WIN32) && !defined(WIN32_LEAN_AND_MEAN)
#define WIN32_LEAN_AND_MEAN  // TBB's header includes windows.h: without its RPC and COM parts and their macros
#endif
#include <tbb/enumerable_thread_specific.h>
#ifdef _WIN32
#undef near  // windows.h's empty `near` and `far` (16-bit pointer qualifiers) are names in the toolkit's code
#undef far
#endif

namespace dqj {

/// `scratch.local()` is the calling thread's object (default-constructed on its first use).
template <typename T>
using ThreadScratch = tbb::enumerable_thread_specific<T>;

}  // namespace dqj
