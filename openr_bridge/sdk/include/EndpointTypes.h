/* Networking is not part of the simulated robot: see the README, "What the host runtime emulates". */
#error "EndpointTypes.h: aibo-sim's host OPEN-R SDK does not emulate networking (ANT and its TCP, UDP, DNS and IP endpoints)"
