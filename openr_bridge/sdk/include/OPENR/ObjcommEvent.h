/* ObjcommEvent.h: what the user's Connect, Control, Ready and Notify functions receive. */
#ifndef _ObjcommEvent_h_DEFINED
#define _ObjcommEvent_h_DEFINED

#include <OPENR/ObjcommTypes.h>
#include <OPENR/ObjcommMessages.h>
#include <OPENR/OSubjectInfo.h>

class OConnectEvent {
public:
    OConnectEvent(int index, const char* name, OConnectCmd command)
        : obsIndex_(index), subName_(name), command_(command) {}
    int         ObsIndex() const { return obsIndex_; }
    const char* SubName() const { return subName_; }
    bool        IsConnect() const { return command_ == oconnectcmdCONNECT; }
    bool        IsDisconnect() const { return command_ != oconnectcmdCONNECT; }

private:
    int         obsIndex_;
    const char* subName_;
    OConnectCmd command_;
};

class OControlEvent {
public:
    OControlEvent(int index, const char* name, ObjcommCommand command)
        : sbjIndex_(index), subName_(name), command_(command) {}
    OControlEvent(int index, ObserverID id, const char* name, ObjcommCommand command)
        : sbjIndex_(index), observerID_(id), subName_(name), command_(command) {}
    int               SbjIndex() const { return sbjIndex_; }
    const char*       SubName() const { return subName_; }
    /* each way of adding or removing: observers connect with the _V22 commands */
    bool IsAddObserver() const {
        return command_ == objcommCMD_ADDOBSERVER || command_ == objcommCMD_ADDOBSERVER_SELF ||
               command_ == objcommCMD_ADDOBSERVER_V22;
    }
    bool IsRemoveObserver() const {
        return command_ == objcommCMD_REMOVEOBSERVER || command_ == objcommCMD_REMOVEOBSERVER_SELF ||
               command_ == objcommCMD_REMOVEOBSERVER_V22;
    }
    const ObserverID& SenderID() const { return observerID_; }

private:
    int            sbjIndex_;
    ObserverID     observerID_;
    const char*    subName_;
    ObjcommCommand command_;
};

class OReadyEvent {
public:
    OReadyEvent(int index, ObserverID id, ObjcommCommand command) : sbjIndex_(index), observerID_(id), command_(command) {}
    int               SbjIndex() const { return sbjIndex_; }
    const ObserverID& SenderID() const { return observerID_; }
    bool              IsAssert() const { return command_ == objcommCMD_ASSERT_READY; }
    bool              IsDeassert() const { return command_ == objcommCMD_DEASSERT_READY; }

private:
    int            sbjIndex_;
    ObserverID     observerID_;
    ObjcommCommand command_;
};

class ONotifyEvent {
public:
    ONotifyEvent() : obsIndex_(0), nData_(0), nNotify_(0) {}
    void SetIndex(int i) { obsIndex_ = i; }
    void SetSubjectInfo(const OSubjectInfo& s) { subjectInfo_ = s; }
    void SetNumOfData(int n) { nData_ = n; }
    void SetNumOfNotify(int n) { nNotify_ = n; }
    void SetData(int index, RCRegion* r) { data_[index] = r; }

    int                 ObsIndex() const { return obsIndex_; }
    const OSubjectInfo& SenderID() const { return subjectInfo_; }
    int                 NumOfData() const { return nData_; }
    int                 NumOfNotify() const { return nNotify_; }
    const void*         Data(int i) const { return data_[i]->Base(); }
    /* the data's addresses, an array (one for all events: filled by each call) */
    const void** Data() const {
        static const void* bases[MAX_NUM_DATA];
        for (int i = 0; i < nData_; i++) bases[i] = data_[i]->Base();
        return bases;
    }
    RCRegion*           RCData(int i) const { return data_[i]; }

private:
    int          obsIndex_;
    OSubjectInfo subjectInfo_;
    int          nData_;
    int          nNotify_;
    RCRegion*    data_[MAX_NUM_DATA];
};

#endif /* _ObjcommEvent_h_DEFINED */
