#!/bin/sh
# Runs tests/test-gui-dialog (the localscan_drift dialog, photographed to
# tests/gui-dialog.png) on a private virtual X display of 24-bit colour.
# Copyright (C) 2026 The gwy-localscan authors.
# SPDX-License-Identifier: GPL-2.0-or-later
program=${TEST_GUI_DIALOG:-./tests/test-gui-dialog}
if ! command -v xvfb-run >/dev/null 2>&1 || ! command -v Xvfb >/dev/null 2>&1; then
    echo "test-gui-dialog: SKIPPED: Xvfb (package xvfb) is not installed"
    exit 77
fi
# xvfb-run -a looks for a free display from :99 up without locking, so two
# runs started together (make -j, test-module-dialog) can pick the same one;
# this one starts its search elsewhere.  Every test connects from its own
# process: -noreset keeps the server from resetting (and refusing the next
# connection) whenever one of them leaves.
exec xvfb-run -a -n $((100 + $$ % 800)) -s "-screen 0 1280x1024x24 -noreset" "$program"
