/* dqjulia/export.h - symbol visibility for libdqjulia.
 * The library is built with hidden visibility so that the symbols of its
 * dependencies (TBB, OpenEXR, OpenVDB) never leak; only what is marked DQJ_API
 * is exported: the C ABI and the C++ API beside it.
 * Windows: programs of the build that link the static library (the command, the tests) see
 * DQJ_STATIC and import nothing; dqjulia.dll exports the C ABI by its module-definition file
 * (core/CMakeLists.txt), and its users import it. */
#ifndef DQJULIA_EXPORT_H
#define DQJULIA_EXPORT_H

/* why: a public header, included by users' programs that do not see core/src/platform; the
 * compiler's own keywords (__declspec, __attribute__) differ by system. */
#if defined(_WIN32)
#if defined(DQJ_STATIC)
#define DQJ_API
#elif defined(DQJ_BUILDING_LIBRARY)
#define DQJ_API __declspec(dllexport)
#else
#define DQJ_API __declspec(dllimport)
#endif
#else
#define DQJ_API __attribute__((visibility("default")))
#endif

#endif
