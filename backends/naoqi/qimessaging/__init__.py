"""naoloc's own implementation of libqi's wire protocol (QiMessaging), pure Python.

Reaches a real NAO (or any libqi endpoint) from any OS and any Python, without the
``qi`` package, and serves the virtual NAOqi to real libqi clients. Modules:
:mod:`.message` (the 28-byte header), :mod:`.signature` (the type grammar),
:mod:`.codec` (the binary format), :mod:`.meta` (MetaObject and ServiceInfo),
:mod:`.capability` (the capability map and login), :mod:`.connection` (one socket and
its reader thread), :mod:`.client` (the qi.Session shape) and :mod:`.server` (a
service directory and served objects).
"""
