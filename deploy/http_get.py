#!/usr/bin/python3
"""Prints the body of an HTTP GET (curl is not among the packages we install)."""
import sys
import urllib.request

if len(sys.argv) != 2 or sys.argv[1] in ("-h", "--help"):
    print("usage: http_get.py URL", file=sys.stderr)
    sys.exit(2)
try:
    sys.stdout.write(urllib.request.urlopen(sys.argv[1], timeout=10).read().decode())
except OSError as error:
    print(f"http_get.py: {sys.argv[1]}: {error}", file=sys.stderr)
    sys.exit(1)
