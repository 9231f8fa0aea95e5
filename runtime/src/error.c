/* Status strings and error messages. */
#include "internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *sluice_status_string(sluice_status status)
{
    switch (status) {
    case SLUICE_OK:
        return "ok";
    case SLUICE_ERROR_INVALID_ARGUMENT:
        return "invalid argument";
    case SLUICE_ERROR_NO_DEVICE:
        return "no OpenCL device";
    case SLUICE_ERROR_OUT_OF_MEMORY:
        return "out of memory";
    case SLUICE_ERROR_BUILD:
        return "OpenCL build error";
    case SLUICE_ERROR_NOT_FOUND:
        return "not found";
    case SLUICE_ERROR_IO:
        return "input/output error";
    case SLUICE_ERROR_OVERFLOW:
        return "stream overflow";
    case SLUICE_ERROR_OPENCL:
        return "OpenCL error";
    case SLUICE_ERROR_LIMIT:
        return "limit reached";
    }
    return "unknown status";
}

sluice_status sl_fail(sluice_context *ctx, sluice_status status, const char *fmt, ...)
{
    if (ctx) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(ctx->error, sizeof ctx->error, fmt, ap);
        va_end(ap);
    }
    return status;
}

const char *sl_cl_error_string(cl_int err)
{
    switch (err) {
#define E(x)                                                                                       \
    case x:                                                                                        \
        return #x;
        E(CL_SUCCESS)
        E(CL_DEVICE_NOT_FOUND)
        E(CL_DEVICE_NOT_AVAILABLE)
        E(CL_COMPILER_NOT_AVAILABLE)
        E(CL_MEM_OBJECT_ALLOCATION_FAILURE)
        E(CL_OUT_OF_RESOURCES)
        E(CL_OUT_OF_HOST_MEMORY)
        E(CL_PROFILING_INFO_NOT_AVAILABLE)
        E(CL_BUILD_PROGRAM_FAILURE)
        E(CL_INVALID_VALUE)
        E(CL_INVALID_DEVICE)
        E(CL_INVALID_CONTEXT)
        E(CL_INVALID_COMMAND_QUEUE)
        E(CL_INVALID_MEM_OBJECT)
        E(CL_INVALID_BUFFER_SIZE)
        E(CL_INVALID_PROGRAM)
        E(CL_INVALID_PROGRAM_EXECUTABLE)
        E(CL_INVALID_KERNEL_NAME)
        E(CL_INVALID_KERNEL)
        E(CL_INVALID_ARG_INDEX)
        E(CL_INVALID_ARG_VALUE)
        E(CL_INVALID_ARG_SIZE)
        E(CL_INVALID_KERNEL_ARGS)
        E(CL_INVALID_WORK_GROUP_SIZE)
        E(CL_INVALID_WORK_ITEM_SIZE)
        E(CL_INVALID_GLOBAL_OFFSET)
        E(CL_INVALID_EVENT)
        E(CL_INVALID_OPERATION)
        E(CL_INVALID_BUILD_OPTIONS)
        E(CL_INVALID_GLOBAL_WORK_SIZE)
        E(CL_PLATFORM_NOT_FOUND_KHR)
#undef E
    }
    return "unknown OpenCL error";
}

sluice_status sl_cl_fail(sluice_context *ctx, cl_int err, const char *what)
{
    sluice_status st = SLUICE_ERROR_OPENCL;
    if (err == CL_MEM_OBJECT_ALLOCATION_FAILURE || err == CL_OUT_OF_HOST_MEMORY ||
        err == CL_INVALID_BUFFER_SIZE || err == CL_OUT_OF_RESOURCES)
        st = SLUICE_ERROR_OUT_OF_MEMORY;
    return sl_fail(ctx, st, "%s failed: %s (%d)", what, sl_cl_error_string(err), (int)err);
}

char *sl_strdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}
