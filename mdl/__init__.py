"""The MDL language: a front end for NVIDIA's Material Definition Language (MDL 1.x).

It reads modules as the *MDL Handbook* writes them and checks them as an MDL compiler
does, with diagnostics in the pwc-list tools' form (``file:line:col``, the quoted line,
a fix):

* :mod:`mdl.lexer`, :mod:`mdl.parser`, :mod:`mdl.ast`, :mod:`mdl.printer` -- text to
  syntax trees and back;
* :mod:`mdl.types`, :mod:`mdl.entities`, :mod:`mdl.checker` -- names, types, overloads,
  uniform and varying, constants folded;
* :mod:`mdl.loader` -- finding modules (beside the importer, search folders, providers)
  and the cache of checked modules by content;
* :mod:`mdl.stdlib` (the standard modules' declarations), :mod:`mdl.mathlib` (``::math``
  over lanes), :mod:`mdl.lanes` and :mod:`mdl.construct` (values over lanes);
* :mod:`mdl.commands` -- ``pwc mdl check`` and ``pwc mdl info``.

It does not import the renderer: a back end (the workbench's is :mod:`render.mdlc`)
provides its own modules and compiles checked modules, through the ``pwc.mdl`` entry
point.
"""
