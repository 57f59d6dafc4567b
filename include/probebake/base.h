/* probebake base types: results, errors, logging (see probebake.h). */
#ifndef PROBEBAKE_BASE_H
#define PROBEBAKE_BASE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PB_VERSION_MAJOR 0
#define PB_VERSION_MINOR 1
#define PB_VERSION_PATCH 0
#define PB_VERSION_STRING "0.1.0"

typedef enum pb_result {
    PB_OK = 0,
    PB_ERROR_INVALID_ARGUMENT,   /* a parameter or descriptor field is out of range */
    PB_ERROR_IO,                 /* a file could not be read or written */
    PB_ERROR_PARSE,              /* malformed input file */
    PB_ERROR_UNSUPPORTED,        /* valid input using something we do not implement */
    PB_ERROR_OUT_OF_HOST_MEMORY,
    PB_ERROR_NO_DEVICE,          /* no Vulkan device, or none matching --device */
    PB_ERROR_DEVICE_LOST,
    PB_ERROR_OUT_OF_DEVICE_MEMORY,
    PB_ERROR_TOO_LARGE,          /* work refused before allocation: exceeds a device limit */
    PB_ERROR_VULKAN,             /* any other Vulkan failure */
    PB_ERROR_CANCELLED,
    PB_RESULT_COUNT
} pb_result;

/* One-line error report. `message` always ends in '\0'. */
typedef struct pb_error {
    pb_result code;
    char message[512];
} pb_error;

/* Stable name of a result code ("PB_ERROR_PARSE"). Never NULL. */
const char *pb_result_name(pb_result r);

typedef enum pb_log_level {
    PB_LOG_DEBUG = 0,
    PB_LOG_INFO,
    PB_LOG_WARN,
    PB_LOG_ERROR
} pb_log_level;

/* Log sink. `message` is one line without a trailing newline. */
typedef void (*pb_log_fn)(pb_log_level level, const char *message, void *user_data);

typedef struct pb_log {
    pb_log_fn fn;      /* NULL: messages are dropped */
    void *user_data;
} pb_log;

#ifdef __cplusplus
}
#endif
#endif
