#include <errno.h>
#include <stdio.h>
#include <fstream>
#include <OPENR/OPENRAPI.h>
#include <OPENR/OSyslog.h>
#include "FileProbe.h"

static void Write(const char* path, const char* text) {
    FILE* file = fopen(path, "w");
    if (file == NULL) {
        OSYSPRINT(("write %s: refused (errno %d)\n", path, errno));
        return;
    }
    fputs(text, file);
    fclose(file);
    OSYSPRINT(("write %s: ok\n", path));
}

static void Read(const char* path) {
    char line[64] = "";
    FILE* file = fopen(path, "r");
    if (file == NULL) {
        OSYSPRINT(("read %s: refused (errno %d)\n", path, errno));
        return;
    }
    if (fgets(line, sizeof line, file) == NULL) line[0] = 0;
    fclose(file);
    OSYSPRINT(("read %s: %s", path, line));
}

OStatus FileProbe::DoStart(const OSystemEvent&) {
    char design[orobotdesignNAME_MAX + 1];
    OPENR::GetRobotDesign(design);
    OSYSPRINT(("design %s\n", design));
    ODesignDataID id;
    byte* data;
    size_t size;
    if (OPENR::FindDesignData("PROBE_TEXT", &id, &data, &size) == oSUCCESS) {
        OSYSPRINT(("design data %u bytes: %.*s", (unsigned)size, (int)size, (const char*)data));
        OPENR::DeleteDesignData(id);
    }
    OSYSPRINT(("missing design data: %u\n", (unsigned)OPENR::FindDesignData("NO_SUCH_KEY", &id, &data, &size)));
    Write("/ms/open-r/mw/data/p/probe.txt", "on the stick\n");
    Read("/MS/OPEN-R/MW/DATA/P/PROBE.TXT");
    Write("/MS/OPEN-R/MW/DATA/P/longer_name.txt", "no\n");
    Write("/MS/OPEN-R/MW/DATA/P/A+B.TXT", "no\n");  // '+' is no character of the stick's names
    Write("here.txt", "in the run's folder\n");
    std::ofstream stream("/MS/OPEN-R/MW/DATA/P/STREAM.TXT");
    stream << "through a C++ stream\n";
    stream.close();
    Read("/MS/OPEN-R/MW/DATA/P/STREAM.TXT");
    Read("/etc/hostname");
    FILE* unclosed = fopen("/MS/OPEN-R/MW/DATA/P/UNCLOSED.TXT", "w");
    fputs("written when the object's process ends\n", unclosed);
    printf("printf %d\n", 7);
    printf("two ");
    printf("parts\n");
    puts("puts");
    printf("c");  // the compiler calls putchar('c'), then putchar('\n')
    printf("\n");
    Write("../escape.txt", "no\n");
    Write("/MS/../escape.txt", "no\n");
    OPENR::Shutdown(OBootCondition(obcbPAUSE_SW));
    return oSUCCESS;
}
