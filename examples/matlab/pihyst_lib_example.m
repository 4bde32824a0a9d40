% pihyst_lib_example.m - a pihyst model and its compensator from MATLAB, through the
% shared library's plain C ABI (csrc/lib/pihyst_lib.h; docs/export.md).
%
% Before running, in a shell at the repository root:
%     make -C csrc shared                                        % -> csrc/libpihyst.so
%     pihyst export examples/paper_table1_multislope.json --flat -o multislope.pihyst
% (On Windows build pihyst.dll from the same sources with the same flags.)
% MATLAB's loadlibrary needs a supported C compiler (mex -setup). GNU Octave has no
% loadlibrary: there, call the library from an .oct/.mex wrapper instead.

libdir = fullfile('..', '..', 'csrc');
if ~libisloaded('libpihyst')
    loadlibrary(fullfile(libdir, 'libpihyst.so'), fullfile(libdir, 'lib', 'pihyst_lib.h'), ...
                'includepath', libdir);
end
assert(calllib('libpihyst', 'pihyst_lib_abi_version') == 3, 'unexpected pihyst ABI version');

status = libpointer('int32Ptr', 0);
h = calllib('libpihyst', 'pihyst_lib_load', 'multislope.pihyst', status);
if status.Value ~= 0
    error('pihyst: %s', calllib('libpihyst', 'pihyst_lib_status_text', status.Value));
end

% The model's loop on the paper's 0-150-0 V triangle (the model's state advances).
u = [0:150, 149:-1:0];
y = libpointer('doublePtr', zeros(size(u)));
s = calllib('libpihyst', 'pihyst_lib_predict', h, u, y, numel(u));
assert(s == 0, calllib('libpihyst', 'pihyst_lib_status_text', s));
fprintf('%.2f um at 150 V, %.2f um back at 0 V\n', y.Value(151), y.Value(end));  % 41.38, 0.00

% Feedforward: the voltages that make the model follow a 0-30-10-35 um path, within
% 0-150 V and at most 0.5 V per sample, from rest.
calllib('libpihyst', 'pihyst_lib_reset', h, [], 0);
s = calllib('libpihyst', 'pihyst_lib_compensator_start', h, 0, 150, 0.5, 0);
assert(s == 0, calllib('libpihyst', 'pihyst_lib_status_text', s));
desired = [linspace(0, 30, 1000), linspace(30, 10, 1000), linspace(10, 35, 1000)];
volts = libpointer('doublePtr', zeros(size(desired)));
flags = libpointer('uint8Ptr', zeros(size(desired), 'uint8'));
n_flagged = calllib('libpihyst', 'pihyst_lib_compensate', h, desired, volts, flags, ...
                    numel(desired));
fprintf('%d of %d samples not reached (slew or range), voltage %.3f .. %.3f V\n', ...
        n_flagged, numel(desired), min(volts.Value), max(volts.Value));

calllib('libpihyst', 'pihyst_lib_free', h);
unloadlibrary('libpihyst');
