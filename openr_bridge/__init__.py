"""The robot side of aibo-sim: Sony OPEN-R's camera messages, wiring and the Webots wrapper.

It works on RGB frames or message bytes from any source and imports neither mujoco nor
aibo_sim. Per camera frame::

    system = OpenRSystem.from_memory_stick()            # the shipped memory stick by default
    system.robot_comm.publish_image(encode_frame(rgb, frame_number=n))
    rgb_bytes = system.controller.camera_get_image()   # the report's camera function
"""

from .cdt import (
    ERS7_CDT_CHANNELS,
    OCdtInfo,
    OCdtVectorData,
    cdt_layer,
    ocdtCHANNEL0,
    ocdtCHANNEL1,
    ocdtCHANNEL2,
    ocdtCHANNEL3,
    ocdtCHANNEL4,
    ocdtCHANNEL5,
    ocdtCHANNEL6,
    ocdtCHANNEL7,
    ocdtCHANNEL_UNDEF,
    ocdtINIT,
    ocdtMAX_Y_SEGMENT,
    ocdtNUM_CHANNELS,
    orange_ball_cdt,
    pink_ball_cdt,
)
from .colour import rgb_to_ycrcb, ycrcb_to_rgb, ycrcb_to_rgb_bt601
from .config import (
    Connection,
    Service,
    ServiceName,
    StubConfig,
    find_connect_cfg,
    load_connect_cfg,
    load_stub_cfg,
    parse_connect_cfg,
    parse_stub_cfg,
)
from .encoder import encode_frame, encode_ycrcb, haar_analysis, reconstruct_luma
from .errors import (
    CdtError,
    ConfigError,
    FrameError,
    ImageAccessError,
    MessageFormatError,
    NoImageError,
    NotConnectedError,
    OpenRError,
    PrimitiveError,
)
from .ers7_camera import (
    CAMERA_DEFAULTS,
    CAMERA_LOCATOR,
    CAMERA_SETTINGS,
    FIELD_OF_VIEW,
    FRAME_RATE_HZ,
    FRAME_TICK_MS,
    FULL_HEIGHT,
    FULL_WIDTH,
    HORIZONTAL_FOV_DEG,
    LAYER_NAMES,
    LAYER_SIZE,
    LAYER_TYPE,
    VERTICAL_FOV_DEG,
    frame_number_for_image,
    ocamparamGAIN_HIGH,
    ocamparamGAIN_LOW,
    ocamparamGAIN_MID,
    ocamparamSHUTTER_FAST,
    ocamparamSHUTTER_MID,
    ocamparamSHUTTER_SLOW,
    ocamparamWB_FL_MODE,
    ocamparamWB_INDOOR_MODE,
    ocamparamWB_OUTDOOR_MODE,
    oprmreqCAM_SET_GAIN,
    oprmreqCAM_SET_SHUTTER_SPEED,
    oprmreqCAM_SET_WHITE_BALANCE,
)
from .image import (
    TAG_LENGTH,
    ODataVectorInfo,
    OFbkImage,
    OFbkImageInfo,
    OFbkImageVectorData,
    odataCDT,
    odataCDT_VECTOR,
    odataFBK_CDT,
    odataFBK_YCrCb,
    odataFBK_YCrCb_HPF,
    odataFBKIMAGE_VECTOR,
    ofbkimageBAND_Cb,
    ofbkimageBAND_CDT,
    ofbkimageBAND_Cr,
    ofbkimageBAND_Y,
    ofbkimageBAND_Y_HH,
    ofbkimageBAND_Y_HL,
    ofbkimageBAND_Y_LH,
    ofbkimageLAYER_C,
    ofbkimageLAYER_H,
    ofbkimageLAYER_L,
    ofbkimageLAYER_M,
    restore_tag_pixels,
)
from .primitive import (
    OPENR,
    OCameraPrimitive,
    OPrimitive,
    OPrimitiveControl_CameraParam,
    check,
    ocamparamUNDEF,
    oFAIL,
    oINVALID_ARG,
    oINVALID_PRIMITIVE_ID,
    oINVALID_REQUEST,
    oNOT_FOUND,
    oNOT_SUPPORTED,
    oOUT_OF_RANGE,
    oprimitiveID_UNDEF,
    oprmreqCAM_AE_OFF,
    oprmreqCAM_AE_ON,
    oprmreqCAM_AWB_OFF,
    oprmreqCAM_AWB_ON,
    oprmreqCAM_GET_CDT_TABLE,
    oSUCCESS,
    sizeof,
    status_name,
)
from .system import DEFAULT_MEMORY_STICK, OpenRSystem
from .wiring import ONotifyEvent, OObject, OObserver, OSubject, OVirtualRobotComm
from .wrapper import (
    CAMERA_CONNECTION,
    CAMERA_SETTING_FUNCTIONS,
    Controller,
    camera_image_get_blue,
    camera_image_get_green,
    camera_image_get_red,
)
