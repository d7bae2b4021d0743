/* OSubjectInfo.h: what an observer knows of a subject it is connected to. */
#ifndef OSubjectInfo_h_DEFINED
#define OSubjectInfo_h_DEFINED

#include <OPENR/ObjcommTypes.h>

class OSubjectInfo : public SubjectID {
public:
    OSubjectInfo() : SubjectID(), version_(objcommVERSION_UNDEF) {}
    OSubjectInfo(const SubjectID& id, ObjcommVersion v) : SubjectID(id), version_(v) {}
    const SubjectID& GetSubjectID() const { return *this; }
    ObjcommVersion   GetVersion() const { return version_; }

private:
    ObjcommVersion version_;
};

#endif
