"""The old SDK's top-level modules for Python 3: ``naoqi``, ``motion``, ``almath``,
``vision_definitions``.

naoloc never imports them under these names: the launcher ``python -m naoloc.run
script.py`` puts this folder on ``sys.path`` (unless Aldebaran's own ``naoqi`` is
importable, which then wins), so a script's ``from naoqi import ALProxy`` finds
:mod:`naoloc.backends.naoqi.oldsdk`.
"""
