# One test object in Sony's form: NAME (the object and its files), BIN (its name on the stick).
OPENRSDK_ROOT?=/usr/local/OPEN_R_SDK
INSTALLDIR?=../MS
CXX=$(OPENRSDK_ROOT)/bin/mipsel-linux-g++
STRIP=$(OPENRSDK_ROOT)/bin/mipsel-linux-strip
MKBIN=$(OPENRSDK_ROOT)/OPEN_R/bin/mkbin
STUBGEN=$(OPENRSDK_ROOT)/OPEN_R/bin/stubgen2
MKBINFLAGS=-p $(OPENRSDK_ROOT)
LIBS=-L$(OPENRSDK_ROOT)/OPEN_R/lib -lObjectComm -lOPENR
CXXFLAGS=-O2 -g -Wall -I. -I$(OPENRSDK_ROOT)/OPEN_R/include/R4000 -I$(OPENRSDK_ROOT)/OPEN_R/include

.PHONY: all install clean

all: $(NAME).bin

%.o: %.cc
	$(CXX) $(CXXFLAGS) -o $@ -c $<

$(NAME)Stub.cc: stub.cfg
	$(STUBGEN) stub.cfg

$(NAME)Stub.o: $(NAME)Stub.cc
$(NAME).o: $(NAME)Stub.cc

$(NAME).bin: $(NAME)Stub.o $(NAME).o $(NAME).ocf
	$(MKBIN) $(MKBINFLAGS) -o $@ $^ $(LIBS)
	$(STRIP) $@

install: $(NAME).bin
	mkdir -p $(INSTALLDIR)/OPEN-R/MW/OBJS
	gzip -c $(NAME).bin > $(INSTALLDIR)/OPEN-R/MW/OBJS/$(BIN).BIN

clean:
	rm -f *.o *.bin $(NAME)Stub.h $(NAME)Stub.cc def.h entry.h
