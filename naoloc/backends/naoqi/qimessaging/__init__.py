"""naoloc's own implementation of libqi's wire protocol (QiMessaging), pure Python.

Reaches a real NAO (or any libqi endpoint) from any OS and any Python, without the
``qi`` package, and serves the virtual NAOqi to real libqi clients. Modules:
:mod:`.message` (the 28-byte header), :mod:`.signature` (the type grammar),
:mod:`.codec` (the binary format), :mod:`.meta` (MetaObject and ServiceInfo),
:mod:`.capability` (the capability map and login), :mod:`.connection` (one socket and
its reader thread), :mod:`.proxy` (remote objects: methods, overloads, signals,
properties), :mod:`.client` (the qi.Session shape), :mod:`.server` (a service
directory and served objects) and :mod:`.memory` (ALMemory subscriber objects).

The protocol follows libqi's public description (design/network-binary-protocol) and
the bytes real libqi 3.1.5 peers exchange on loopback (see
``tests/test_qimessaging_format.py``).
"""
