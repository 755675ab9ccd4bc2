1;  % script file: Octave peer of bench/modes_accuracy.cpp (issue 7 §4, docs/accuracy-vs-time.md)
% usage: octave --no-gui -q bench/peers/octave_modes.m DIR NAME
% DIR = OUT/modes_data/NAME with {M,K,wref}.mtx written by modes_accuracy (K v = w^2 M v,
% undamped). Prints CSV lines: octave,NAME,n,k,method,seconds,err_lowest_k
%   polyeig   [X, e] = polyeig(K, 0, M): the quadratic problem with vectors (like the full QZ)
%   eig       [V, D] = eig(K, M): the symmetric-definite generalized problem (like dsygvd)
%   eigs      eigs(sparse K, sparse M, k, 'sm'): the lowest k only (ARPACK, like dsygvx)
% All with eigenvectors. Times are medians of 3 runs (1 when a run exceeds 20 s); polyeig is
% skipped above n = 300, as our full QZ.
args = argv();
dir = args{1};
name = args{2};
addpath(fileparts(mfilename('fullpath')));
warning('off', 'all');
M = read_mm([dir '/M.mtx']); K = read_mm([dir '/K.mtx']); wref = read_mm([dir '/wref.mtx']);
n = rows(M); k = numel(wref);

function e = err_of(w, wref)
  w = sort(w(:));
  if numel(w) < numel(wref)
    e = NaN;
  else
    e = max(abs(w(1:numel(wref)) - wref(:)) ./ wref(:));
  end
end

function e = polyeig_vectors(K, M)
  [X, e] = polyeig(K, zeros(rows(K)), M);
end

function d = eig_vectors(K, M)
  [V, D] = eig(K, M);
  d = diag(D);
end

function d = eigs_vectors(K, M, k)
  [V, D] = eigs(K, M, k, 'sm');
  d = diag(D);
end

function [t, out] = timed(f)
  t = []; out = [];
  for r = 1:3
    tic; out = f(); t(end + 1) = toc;
    if t(end) > 20
      break;
    end
  end
  t = median(t);
end

if n <= 300  % like our full QZ: polyeig of n = 1000 takes minutes (230 s on the 2-core machine)
  [t, e] = timed(@() polyeig_vectors(K, M));
  w = sort(abs(e)); w = w(1:2:end);  % each w appears as +-iw
  printf('octave,%s,%d,%d,polyeig,%.4g,%.4g\n', name, n, k, t, err_of(w, wref)); fflush(stdout);
else
  printf('octave,%s,%d,%d,polyeig,skipped,nan\n', name, n, k); fflush(stdout);
end
[t, d] = timed(@() eig_vectors(K, M));
printf('octave,%s,%d,%d,eig,%.4g,%.4g\n', name, n, k, t, err_of(sqrt(d), wref)); fflush(stdout);
if n > k
  Ks = sparse(K); Ms = sparse(M);
  try
    [t, d] = timed(@() eigs_vectors(Ks, Ms, k));
    printf('octave,%s,%d,%d,eigs,%.4g,%.4g\n', name, n, k, t, err_of(sqrt(abs(d)), wref));
  catch err
    printf('octave,%s,%d,%d,eigs,nan,nan\n', name, n, k);
  end
end
