/*
 * interpose.c: the C library's file calls, as objects see them. libOPENR defines them, so an
 * object's calls (and the C++ library's, on its behalf) come here first; each maps its path with
 * aibo_openr_object_path (msfs.cc: /MS is the memory stick, a relative path the run's folder,
 * anything else refused) and calls the C library's own. gets() reads the run's console input
 * (standard input), and ends the object (abort) at its end.
 * printf, vprintf, puts and putchar (what compilers turn a printf into) of an object write to its
 * console, as OSYSPRINT does: stamped with the simulated time and its name, into console.log too
 * (not a putchar of the source, which glibc inlines into the stream's buffer, nor std::cout).
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#define PATH_STORAGE 4096

int aibo_openr_object_path(const char* path, int create, char* storage, size_t size, const char** mapped);
int aibo_openr_print(const char* text); /* kernel.cc: 0 for the runtime's own calls, not an object's */

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
    if (c == EOF && end == line) {
        /* The robot's console waits for the next line, and programs written for it ask again or
         * go on with a line they did not get: once standard input has ended, the object ends. */
        fputs("aibo-sim: gets(): the console's input (standard input) has ended: give what the "
              "program asks on standard input\n", stderr);
        abort();
    }
    *end = 0;
    return line;
}

int vprintf(const char* format, va_list arguments) {
    char line[1024];
    va_list again;
    va_copy(again, arguments);
    int length = vsnprintf(line, sizeof line, format, arguments);
    char* text = length >= 0 && (size_t)length >= sizeof line ? malloc((size_t)length + 1) : line;
    if (text != line && text != NULL) vsnprintf(text, (size_t)length + 1, format, again);
    va_end(again);
    if (length < 0 || text == NULL) return -1;
    if (!aibo_openr_print(text)) fputs(text, stdout);
    if (text != line) free(text);
    return length;
}

int printf(const char* format, ...) {
    va_list arguments;
    va_start(arguments, format);
    int length = vprintf(format, arguments);
    va_end(arguments);
    return length;
}

int puts(const char* text) {
    if (!aibo_openr_print(text)) return fputs(text, stdout) < 0 ? EOF : putc('\n', stdout);
    aibo_openr_print("\n");
    return 1;
}

int putchar(int c) {
    char text[2] = {(char)c, 0};
    if (c == 0 || !aibo_openr_print(text)) return putc(c, stdout);
    return c;
}

/* The same, where a program was compiled with _FORTIFY_SOURCE (Ubuntu's default). */
int __vprintf_chk(int flag, const char* format, va_list arguments) {
    (void)flag;
    return vprintf(format, arguments);
}

int __printf_chk(int flag, const char* format, ...) {
    va_list arguments;
    va_start(arguments, format);
    int length = __vprintf_chk(flag, format, arguments);
    va_end(arguments);
    return length;
}
