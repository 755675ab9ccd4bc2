1;  % script file: Octave peer of bench/frf_accuracy.cpp (issue 7 §4, docs/accuracy-vs-time.md)
% usage: octave --no-gui -q bench/peers/octave_frf.m DIR NAME
% DIR = OUT/frf_data/NAME with {M,Q,K,b,c,w,wref,gref}.mtx written by frf_accuracy.
% Prints CSV lines: octave,NAME,n,method,amortized_s_per_freq,err_max,err_median,note
%   freqresp  the control package's freqresp on ss(A, B, C, 0) with A = [0 E; -M\K -M\Q] (the
%             state-space model a user would build; time includes forming it), at the F
%             frequencies of w, median of 3 runs (n >= 300: once, at the 25 of wref);
%   backslash a loop of (K - w^2 M + i w Q) \ b, sparse when n >= 100, median of 3 runs.
% Errors against the 266-bit reference gref at wref (a subset of w).
args = argv();
dir = args{1};
name = args{2};
addpath(fileparts(mfilename('fullpath')));
pkg load control
warning('off', 'all');
M = read_mm([dir '/M.mtx']); Q = read_mm([dir '/Q.mtx']); K = read_mm([dir '/K.mtx']);
b = read_mm([dir '/b.mtx']); C = read_mm([dir '/c.mtx']);
w = read_mm([dir '/w.mtx']); wref = read_mm([dir '/wref.mtx']);
G = read_mm([dir '/gref.mtx']); gref = G(:, 1) + 1i * G(:, 2);
n = rows(M);
F = numel(w);
cy = C(1, :); cv = C(2, :);

function [e_max, e_med] = errs(h, gref)
  e = abs(h(:) - gref(:)) ./ abs(gref(:));
  e(~isfinite(e)) = 1;
  e_max = max(e); e_med = median(e);
end

% freqresp
note = '';
if n >= 300
  reps = 1; wt = wref;  % freqresp of n = 1000 takes about 0.5 s per frequency
else
  reps = 3; wt = w;
end
try
  t = zeros(reps, 1);
  for r = 1:reps
    tic;
    A = [zeros(n) eye(n); -(M \ K) -(M \ Q)];
    sys = ss(A, [zeros(n, 1); M \ b], [cy cv], 0);
    H = freqresp(sys, wt);
    t(r) = toc;
  end
  sys = ss([zeros(n) eye(n); -(M \ K) -(M \ Q)], [zeros(n, 1); M \ b], [cy cv], 0);
  h = freqresp(sys, wref);
  [e_max, e_med] = errs(h, gref);
  if numel(wt) < F
    note = sprintf('timed at %d frequencies; once', numel(wt));
  end
  printf('octave,%s,%d,freqresp,%.4g,%.4g,%.4g,%s\n', name, n, median(t) / numel(wt), e_max, e_med, note);
catch err
  printf('octave,%s,%d,freqresp,nan,nan,nan,failed: %s\n', name, n, strrep(err.message, ',', ';'));
end
fflush(stdout);

% loop of backslash solves
if n >= 100
  Ms = sparse(M); Qs = sparse(Q); Ks = sparse(K); kind = 'sparse';
else
  Ms = M; Qs = Q; Ks = K; kind = 'dense';
end
t = zeros(3, 1);
for r = 1:3
  tic;
  for k = 1:F
    y = (Ks - w(k)^2 * Ms + 1i * w(k) * Qs) \ b;
    z = cy * y + 1i * w(k) * (cv * y);
  end
  t(r) = toc;
end
h = zeros(numel(wref), 1);
for k = 1:numel(wref)
  y = (Ks - wref(k)^2 * Ms + 1i * wref(k) * Qs) \ b;
  h(k) = cy * y + 1i * wref(k) * (cv * y);
end
[e_max, e_med] = errs(h, gref);
printf('octave,%s,%d,backslash_%s,%.4g,%.4g,%.4g,\n', name, n, kind, median(t) / F, e_max, e_med);
