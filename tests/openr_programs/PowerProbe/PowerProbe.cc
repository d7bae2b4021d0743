#include <OPENR/OPENRAPI.h>
#include <OPENR/OPENRMessages.h>
#include <OPENR/OPrimitiveControl.h>
#include <OPENR/OSyslog.h>
#include "PowerProbe.h"
#include "entry.h"

static void Print(const char* what, const OPowerStatus& status) {
    OSYSPRINT(("%s robot 0x%08x battery 0x%04x capacity %u temperature %u full %u voltage %u current %d\n", what,
               (unsigned)status.robotStatus, (unsigned)status.batteryStatus, (unsigned)status.remainingCapacity,
               (unsigned)status.temperature, (unsigned)status.fullyChargedCapacity, (unsigned)status.voltage,
               (int)status.current));
}

// A face light on its A or B face (ControlPrimitive: it stays lit).
static void Light(const char* locator, OLED3Mode mode) {
    OPrimitiveID id;
    OPENR::OpenPrimitive(locator, &id);
    OPrimitiveControl_LEDCommandValue3 led(255, mode);
    OPENR::ControlPrimitive(id, oprmreqLED3_SET_COMMAND, &led, sizeof led, 0, 0);
}

OStatus PowerProbe::DoStart(const OSystemEvent&) {
    Light("PRM:/r1/c1/c2/c3/la-LED3:la", oled3_MODE_B);  // face light 1: green on the B face
    Light("PRM:/r1/c1/c2/c3/ln-LED3:ln", oled3_MODE_B);  // 14: blue
    Light("PRM:/r1/c1/c2/c3/lm-LED3:lm", oled3_MODE_A);  // 13: red on the A face
    OPowerStatus status;
    OPENR::GetPowerStatus(&status);
    Print("status", status);
    OPowerStatus mask;
    mask.Set(orsbMOTOR_POWER, 0, opsoREMAINING_CAPACITY_NOT_NOTIFY, opsoTEMPERATURE_NOT_NOTIFY,
             opsoTIME_DIF_NOT_NOTIFY, opsoVOLUME_NOT_NOTIFY);
    OServiceEntry entry(myOID_, Extra_Entry[entryUpdatePowerStatus]);
    OSYSPRINT(("observe %u\n", (unsigned)OPENR::ObservePowerStatus(mask, entry)));
    OSYSPRINT(("observe again %u\n", (unsigned)OPENR::ObservePowerStatus(mask, entry)));
    OPENR::SetMotorPower(opowerON);
    return oSUCCESS;
}

void PowerProbe::UpdatePowerStatus(void* message) {
    Print("notified", ((OPowerStatusMessage*)message)->powerStatus);
    OServiceEntry entry(myOID_, Extra_Entry[entryUpdatePowerStatus]);
    OSYSPRINT(("unobserve %u\n", (unsigned)OPENR::UnobservePowerStatus(entry)));
    OPENR::SetMotorPower(opowerOFF);  // not reported: no longer observed
}
