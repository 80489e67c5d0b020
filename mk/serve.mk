# serve.mk -- the lab-server suite (tests/serve/run.sh) drives misbehaving clients (idle,
# dripping and probing connections from chosen loopback addresses) with tests/serve/clients.py.
CMDS += python3:python3
