/*
 * msfs.cc: the files an object sees. On the robot the only file system is the Memory Stick,
 * mounted at /MS, FAT with 8.3 names in upper case (a program may spell them in any case). Here
 * /MS/... is the memory-stick folder: each name must be an 8.3 name (as the robot requires, to
 * find a file as to make one), is found ignoring case, and a new file or folder is made in upper case. A relative path is the run's working folder
 * (aibo-sim's --out), as for any aibo-sim controller. Any other path, one that climbs out of
 * its folder with "..", and one through a symbolic link in either folder (a FAT stick has none;
 * one planted in --out could lead anywhere) is refused (errno EACCES) and logged, never opened.
 *
 * interpose.c puts the C library's file calls through this for the objects' code only (the
 * runtime's own files are opened as they are).
 */
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <string.h>
#include <sys/stat.h>
#include <OPENR/OSyslog.h>
#include "host.h"

namespace host {
namespace {

std::string stickRoot, workFolder;
bool insideObject = false;

std::string Upper(const std::string& name) {
    std::string upper(name);
    for (size_t i = 0; i < upper.size(); i++) {
        if (upper[i] >= 'a' && upper[i] <= 'z') upper[i] = (char)(upper[i] - 'a' + 'A');
    }
    return upper;
}

/* Up to 8 characters, then up to 3 after one dot, each a letter, a digit or one of the others
 * Sony's Programmer's Guide (A.1) lists. */
bool Is83(const std::string& name) {
    size_t dot = name.find('.');
    std::string base = name.substr(0, dot), extension = dot == std::string::npos ? "" : name.substr(dot + 1);
    if (base.empty() || base.size() > 8 || extension.size() > 3) return false;
    std::string characters = base + extension;
    for (size_t i = 0; i < characters.size(); i++) {
        unsigned char c = (unsigned char)characters[i];
        if (!isalnum(c) && !strchr("$&#{}~%'()-@^`!_", c)) return false;
    }
    return true;
}

/* The entry of `folder` whose name is `name` ignoring case ("" when none). */
std::string FindIgnoringCase(const std::string& folder, const std::string& name) {
    DIR* directory = opendir(folder.c_str());
    if (directory == NULL) return "";
    std::string found, wanted = Upper(name);
    while (struct dirent* entry = readdir(directory)) {
        if (Upper(entry->d_name) == wanted) {
            found = entry->d_name;
            break;
        }
    }
    closedir(directory);
    return found;
}

std::vector<std::string> Split(const std::string& path) {
    std::vector<std::string> parts;
    size_t start = 0;
    while (start <= path.size()) {
        size_t end = path.find('/', start);
        if (end == std::string::npos) end = path.size();
        std::string part = path.substr(start, end - start);
        if (!part.empty() && part != ".") parts.push_back(part);
        start = end + 1;
    }
    return parts;
}

}  // namespace

void SetMemoryStick(const std::string& root, const std::string& workdir) {
    stickRoot = root;
    workFolder = workdir;
}

bool InObjectCode() { return insideObject; }
void EnterObjectCode(bool inside) { insideObject = inside; }

std::string MapPath(const char* path, bool create, std::string* error) {
    std::string text(path ? path : "");
    bool stick = Upper(text.substr(0, 4)) == "/MS/" || Upper(text) == "/MS";
    if (!stick && !text.empty() && text[0] == '/') {
        *error = "not on the memory stick (/MS)";
        return "";
    }
    std::vector<std::string> parts = Split(stick ? text.substr(3) : text);
    std::vector<std::string> resolved;
    for (size_t i = 0; i < parts.size(); i++) {
        if (parts[i] == "..") {
            if (resolved.empty()) {
                *error = stick ? "climbs out of the memory stick" : "climbs out of the run's folder";
                return "";
            }
            resolved.pop_back();
        } else {
            resolved.push_back(parts[i]);
        }
    }
    std::string mapped = stick ? stickRoot : workFolder;
    for (size_t i = 0; i < resolved.size(); i++) {
        std::string name = resolved[i];
        if (stick) {
            if (!Is83(name)) {  /* the robot refuses it, to create or to find (Programmer's Guide A.1) */
                *error = "not an 8.3 name of letters, digits and $&#{}~%'()-@^`!_ (the memory stick's FAT has no others)";
                return "";
            }
            std::string existing = FindIgnoringCase(mapped, name);
            name = existing.empty() ? Upper(name) : existing;
        }
        mapped += "/" + name;
        struct stat status;
        if (lstat(mapped.c_str(), &status) == 0 && S_ISLNK(status.st_mode)) {
            *error = "a symbolic link (followed by no object: a FAT memory stick has none)";
            return "";
        }
    }
    return mapped;
}

}  // namespace host

/* For interpose.c: in `mapped`, the host path of an object's `path` (in `storage`), or `path`
 * itself for the runtime's own calls; -1 when refused (errno EACCES, the refusal logged). */
extern "C" int aibo_openr_object_path(const char* path, int create, char* storage, size_t size, const char** mapped) {
    *mapped = path;
    if (!host::InObjectCode() || path == NULL) return 0;
    host::SystemCode system;
    std::string error, hostPath = host::MapPath(path, create != 0, &error);
    if (hostPath.empty() || hostPath.size() >= size) {
        osyslog(osyslogERROR, "refused to open %s: %s", path, hostPath.empty() ? error.c_str() : "path too long");
        errno = EACCES;
        return -1;
    }
    memcpy(storage, hostPath.c_str(), hostPath.size() + 1);
    *mapped = storage;
    return 0;
}
