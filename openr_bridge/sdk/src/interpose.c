/*
 * interpose.c: the C library's file calls, as objects see them. libOPENR defines them, so an
 * object's calls (and the C++ library's, on its behalf) come here first; each maps its path with
 * aibo_openr_object_path (msfs.cc: /MS is the memory stick, a relative path the run's folder,
 * anything else refused) and calls the C library's own. gets() reads the run's console input.
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

#define PATH_STORAGE 4096

int aibo_openr_object_path(const char* path, int create, char* storage, size_t size, const char** mapped);

static int creates(const char* mode) { return mode != NULL && (mode[0] == 'w' || mode[0] == 'a'); }

#define MAPPED(variable, path, create, failure) \
    char variable##_storage[PATH_STORAGE]; \
    const char* variable; \
    if (aibo_openr_object_path(path, create, variable##_storage, PATH_STORAGE, &variable) != 0) return failure

#define ORIGINAL(name) \
    static __typeof__(name)* original = NULL; \
    if (original == NULL) original = (__typeof__(name)*)dlsym(RTLD_NEXT, #name)

FILE* fopen(const char* path, const char* mode) {
    ORIGINAL(fopen);
    MAPPED(host, path, creates(mode), NULL);
    return original(host, mode);
}

FILE* fopen64(const char* path, const char* mode) {
    ORIGINAL(fopen64);
    MAPPED(host, path, creates(mode), NULL);
    return original(host, mode);
}

FILE* freopen(const char* path, const char* mode, FILE* stream) {
    ORIGINAL(freopen);
    MAPPED(host, path, creates(mode), NULL);
    return original(host, mode, stream);
}

int open(const char* path, int flags, ...) {
    ORIGINAL(open);
    mode_t mode = 0;
    if (flags & O_CREAT) {
        va_list arguments;
        va_start(arguments, flags);
        mode = (mode_t)va_arg(arguments, int);
        va_end(arguments);
    }
    MAPPED(host, path, (flags & O_CREAT) != 0, -1);
    return original(host, flags, mode);
}

int open64(const char* path, int flags, ...) {
    ORIGINAL(open64);
    mode_t mode = 0;
    if (flags & O_CREAT) {
        va_list arguments;
        va_start(arguments, flags);
        mode = (mode_t)va_arg(arguments, int);
        va_end(arguments);
    }
    MAPPED(host, path, (flags & O_CREAT) != 0, -1);
    return original(host, flags, mode);
}

int creat(const char* path, mode_t mode) {
    ORIGINAL(creat);
    MAPPED(host, path, 1, -1);
    return original(host, mode);
}

int access(const char* path, int mode) {
    ORIGINAL(access);
    MAPPED(host, path, 0, -1);
    return original(host, mode);
}

int stat(const char* path, struct stat* buffer) {
    ORIGINAL(stat);
    MAPPED(host, path, 0, -1);
    return original(host, buffer);
}

int lstat(const char* path, struct stat* buffer) {
    ORIGINAL(lstat);
    MAPPED(host, path, 0, -1);
    return original(host, buffer);
}

DIR* opendir(const char* path) {
    ORIGINAL(opendir);
    MAPPED(host, path, 0, NULL);
    return original(host);
}

int mkdir(const char* path, mode_t mode) {
    ORIGINAL(mkdir);
    MAPPED(host, path, 1, -1);
    return original(host, mode);
}

int rmdir(const char* path) {
    ORIGINAL(rmdir);
    MAPPED(host, path, 0, -1);
    return original(host);
}

int unlink(const char* path) {
    ORIGINAL(unlink);
    MAPPED(host, path, 0, -1);
    return original(host);
}

int remove(const char* path) {
    ORIGINAL(remove);
    MAPPED(host, path, 0, -1);
    return original(host);
}

int truncate(const char* path, off_t length) {
    ORIGINAL(truncate);
    MAPPED(host, path, 0, -1);
    return original(host, length);
}

int rename(const char* from, const char* to) {
    ORIGINAL(rename);
    MAPPED(host_from, from, 0, -1);
    MAPPED(host_to, to, 1, -1);
    return original(host_from, host_to);
}

char* gets(char* line) {
    int c;
    char* end = line;
    while ((c = getchar()) != EOF && c != '\n') *end++ = (char)c;
    if (c == EOF && end == line) return NULL;
    *end = 0;
    return line;
}
